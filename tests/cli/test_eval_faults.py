"""rtaw-eval under faults: files replaced between a run and its resume, a full disk, a
signal, an OS error in a sweep job, and the time estimate of a long run.

Everything runs in-process (the ``cli`` fixture) except the SIGTERM case, which needs a
real signal sent to a real process.
"""

from __future__ import annotations

import errno
import functools
import hashlib
import importlib
import json
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Any, ClassVar

import pytest
from tqdm import tqdm

import rtaw_marl.cli.eval as eval_cli
import rtaw_marl.evaluation.journal as journal_module
from rtaw_marl.evaluation.evaluate import TimeEstimate
from rtaw_marl.evaluation.journal import file_digest, journal_path
from rtaw_marl.policies.labels import checkpoint_labels
from rtaw_marl.policies.pretrained.registry import SHIPPED
from rtaw_marl.utils.signals import Interrupted

pytestmark = pytest.mark.integration

QUICK = ("sim.num_tasks=30", "progress=false")
RTAW_EVAL = Path(sys.executable).with_name("rtaw-eval")
#: The module (the package's ``evaluate`` attribute is the function).
evaluate_module = importlib.import_module("rtaw_marl.evaluation.evaluate")


def _entries(out: Path) -> list[dict[str, Any]]:
    """The journal's episode lines (after its header)."""
    return [json.loads(line) for line in journal_path(out).read_text().splitlines()[1:]]


def _resume_line(message: str) -> str:
    return f"error: resume=true: {{journal}} holds episodes of another setting (differs in {message}); use another output or drop resume"  # noqa: E501


# ------------------------------------------------------------------ files by contents
def test_a_checkpoint_replaced_at_the_same_path_runs_only_its_episodes_again(
    cli, tmp_path: Path
) -> None:
    """The old journal matched ``rtaw:<path>`` and replayed the old network's TTDs; now
    its episodes carry the checkpoint's sha256: the replaced one runs again (and says
    so), mpdm's episodes are replayed."""
    ckpt, out = tmp_path / "policy.pt", tmp_path / "res.json"
    shutil.copy(SHIPPED / "A_astar_m10.pt", ckpt)
    args = [*QUICK, "policy=[mpdm,checkpoint]", f"checkpoint={ckpt}", "seeds=[0,1]"]
    assert cli("eval", *args, f"output={out}").code == 0
    before = json.loads(out.read_text())["policies"]
    shutil.copy(SHIPPED / "A_astar_m10_plus.pt", ckpt)
    result = cli("eval", *args, f"output={out}", "resume=true")
    assert result.code == 0, result.err
    label = checkpoint_labels([str(ckpt)])[0]  # the file's name, not its whole path
    assert f"resume: the file of {label} has changed since 2 of its episodes were " in result.out
    after = json.loads(out.read_text())["policies"]
    assert cli("eval", *args, f"output={tmp_path / 'fresh.json'}").code == 0
    fresh = json.loads((tmp_path / "fresh.json").read_text())["policies"]
    assert after[label]["ttd"] == fresh[label]["ttd"] != before[label]["ttd"]
    assert after["mpdm"]["wall_time_s"] == before["mpdm"]["wall_time_s"]  # replayed
    old, new = file_digest(SHIPPED / "A_astar_m10.pt"), file_digest(ckpt)
    sources = [(e["policy"], e["source"]) for e in _entries(out)]
    assert sources == [("mpdm", None), (label, old)] * 2 + [(label, new)] * 2


def _layout_case(tmp_path: Path) -> tuple[list[str], Path, bytes]:
    path = tmp_path / "map.txt"
    path.write_text("..........\n" * 10)
    return [f"layout.path={path}", "sim.num_robots=2", "tasks=random"], path, b"@" + b"." * 9


def _tasks_case(tmp_path: Path) -> tuple[list[str], Path, bytes]:
    path = tmp_path / "tasks.csv"
    path.write_text("ox,oy,dx,dy\n" + "1,1,5,5\n" * 30)
    return ["tasks=file", f"tasks.path={path}"], path, b"ox,oy,dx,dy\n2,2,5,5"


@pytest.mark.parametrize(
    ("key", "case"), [("layout.path", _layout_case), ("tasks.path", _tasks_case)]
)
def test_an_input_file_replaced_at_the_same_path_refuses_the_resume(
    key: str, case: Any, cli, tmp_path: Path
) -> None:
    """A map or task file is part of the setting by its contents: replaced, the resume
    is refused naming the key and both hashes; moved elsewhere unchanged, it resumes."""
    overrides, path, head = case(tmp_path)
    out = tmp_path / "res.json"
    args = [*QUICK, "policy=[mpdm]", "seeds=[0,1]", f"output={out}"]
    assert cli("eval", *overrides, *args).code == 0
    old = hashlib.sha256(path.read_bytes()).hexdigest()
    moved = tmp_path / "moved" / path.name
    moved.parent.mkdir()
    shutil.copy(path, moved)
    data = path.read_bytes()
    path.write_bytes(head + data[len(head) :])
    new = hashlib.sha256(path.read_bytes()).hexdigest()
    result = cli("eval", *overrides, *args, "resume=true")
    expected = _resume_line(f"{key}: contents sha256 {old[:12]} -> contents sha256 {new[:12]}")
    assert result.code == 2
    assert result.err.strip() == expected.format(journal=journal_path(out))
    same = [o.replace(str(path), str(moved)) for o in overrides]
    result = cli("eval", *same, *args, "resume=true")
    assert result.code == 0, result.err
    assert f"resume: 2 finished episodes from {journal_path(out)}" in result.out


def test_a_path_keyed_journal_is_refused(cli, tmp_path: Path) -> None:
    """A journal of the first format matched files by path: never replayed."""
    out = tmp_path / "res.json"
    header = {"format": "rtaw_marl.episodes/1", "setting": {}}
    episode = {"policy": "mpdm", "seed": 0, "metrics": {"ttd": 517.0}}
    journal_path(out).write_text(json.dumps(header) + "\n" + json.dumps(episode) + "\n")
    result = cli("eval", *QUICK, "policy=[mpdm]", "seeds=[0]", f"output={out}", "resume=true")
    assert result.code == 2
    assert result.err.strip() == (
        f"error: resume=true: {journal_path(out)} is an older journal (rtaw_marl.episodes/1) "
        "that matched episodes by file paths, not contents, so its episodes cannot be "
        "trusted; drop resume=true to run them again"
    )


# ------------------------------------------------------------------ a full disk
class _FillingFile:
    """A binary file whose ``write`` number ``full_at`` writes half its bytes, then
    fails as a full disk does."""

    def __init__(self, path: Path, mode: str, full_at: int) -> None:
        self.inner, self.writes, self.full_at = open(path, mode), 0, full_at  # noqa: SIM115

    def write(self, data: bytes) -> int:
        self.writes += 1
        if self.writes == self.full_at:
            self.inner.write(data[: len(data) // 2])
            self.inner.flush()
            raise OSError(errno.ENOSPC, "No space left on device")
        return self.inner.write(data)

    def __getattr__(self, name: str) -> Any:
        return getattr(self.inner, name)


def test_a_full_disk_while_journalling_is_one_line_and_resume_continues(
    cli, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The third write (header, one episode, then the second) finds the disk full: one
    line naming the journal and what it keeps; the torn line is dropped on resume."""
    out = tmp_path / "res.json"
    args = [*QUICK, "policy=[mpdm]", "seeds=[0,1,2]", f"output={out}"]
    with monkeypatch.context() as patch:
        opener = functools.partial(_FillingFile, full_at=3)
        patch.setattr(journal_module, "open", opener, raising=False)
        result = cli("eval", *args)
    assert result.code == 2
    assert result.err.strip() == (
        f"error: no space left on the device writing {journal_path(out)} (No space left on "
        "device); the journal keeps 1 finished episode: run the same command with "
        "resume=true to continue"
    )
    assert not out.exists()
    resumed = cli("eval", *args, "resume=true")
    assert resumed.code == 0, resumed.err
    assert f"resume: 1 finished episodes from {journal_path(out)}" in resumed.out
    assert [e["seed"] for e in _entries(out)] == [0, 1, 2]


# ------------------------------------------------------------------ signals
@pytest.mark.parametrize(
    ("stop", "status"),
    [(KeyboardInterrupt(), 130), (Interrupted(signum=signal.SIGTERM), 143)],
    ids=["ctrl-c", "sigterm"],
)
def test_an_interrupt_says_what_is_kept_and_how_to_resume(
    stop: KeyboardInterrupt, status: int, cli, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Stopped during the third episode: one line, the two finished episodes in the
    journal, exit 128 + signal."""
    episode, calls = evaluate_module._episode, []

    def stopping(*args: Any) -> Any:
        calls.append(1)
        if len(calls) == 3:
            raise stop
        return episode(*args)

    monkeypatch.setattr(evaluate_module, "_episode", stopping)
    out = tmp_path / "res.json"
    result = cli("eval", *QUICK, "policy=[mpdm]", "seeds=[0,1,2]", f"output={out}")
    assert result.code == status
    assert result.err.strip() == (
        f"interrupted: 2 finished episodes kept in {journal_path(out)}; run the same command "
        "with resume=true to continue"
    )
    assert [e["seed"] for e in _entries(out)] == [0, 1]


@pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals")
def test_sigterm_stops_like_ctrl_c_and_the_run_resumes(tmp_path: Path) -> None:
    """A real SIGTERM (what schedulers send) in the middle of an evaluation: one line,
    exit 143, every finished episode journalled; resume=true replays them."""
    out = tmp_path / "res.json"
    args = [str(RTAW_EVAL), "sim.num_tasks=200", "policy=[mpdm]", "progress=false",
            f"output={out}"]  # fmt: skip
    proc = subprocess.Popen(
        [*args, "seeds=${range:0,400}"],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
    )
    journal = journal_path(out)
    try:
        while proc.poll() is None and (not journal.exists() or journal.read_text().count("\n") < 3):
            time.sleep(0.05)
        proc.send_signal(signal.SIGTERM)
        _, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 143, err
    kept = _entries(out)
    assert len(kept) >= 2
    assert err.strip() == (
        f"interrupted: {len(kept)} finished episodes kept in {journal}; run the same command "
        "with resume=true to continue"
    )
    assert not out.exists()
    seeds = f"seeds=${{range:0,{len(kept) + 1}}}"
    resumed = subprocess.run([*args, seeds, "resume=true"], capture_output=True, text=True,
                             timeout=300)  # fmt: skip
    assert resumed.returncode == 0, resumed.stderr
    assert f"resume: {len(kept)} finished episodes" in resumed.stdout
    ttd = json.loads(out.read_text())["policies"]["mpdm"]["ttd"]
    assert ttd[: len(kept)] == [e["metrics"]["ttd"] for e in kept]
    assert len(ttd) == len(kept) + 1


# ------------------------------------------------------------------ OS errors
def _too_long(spec: Any) -> Any:
    raise OSError(errno.ENAMETOOLONG, "File name too long", "/tmp/" + "x" * 300)


def test_an_os_error_is_one_line_naming_the_file(
    cli, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(eval_cli, "build_sim", _too_long)
    result = cli("eval", *QUICK, "policy=[mpdm]", f"output={tmp_path / 'r.json'}")
    assert result.code == 2
    assert result.err.strip() == f"error: File name too long: /tmp/{'x' * 300}"


def test_an_os_error_in_a_sweep_job_fails_that_job_only(
    cli, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """In a sweep the job prints its line and leaves FAILED; the other job runs; the
    sweep exits 2 with the count (a traceback used to end the sweep)."""
    build = eval_cli.build_sim

    def failing(spec: Any) -> Any:
        return _too_long(spec) if spec.navigator.name == "astar" else build(spec)

    monkeypatch.setattr(eval_cli, "build_sim", failing)
    sweep = tmp_path / "sweep"
    result = cli("eval", "-m", *QUICK, "policy=[mpdm]", "seeds=[0]", "navigator=direct,astar",
                 f"hydra.sweep.dir={sweep}")  # fmt: skip
    assert result.code == 2
    errors = [line for line in result.err.splitlines() if line.startswith("error: ")]
    assert errors == [
        "error: job 1 (sim.num_tasks=30 progress=False policy=[mpdm] seeds=[0] navigator=astar): "
        f"File "
        f"name too long: /tmp/{'x' * 300}",
        f"error: 1 of 2 jobs failed (their errors are above and in {sweep}/*/FAILED)",
    ]
    assert (sweep / "1" / "FAILED").is_file()
    assert (sweep / "0" / "results.json").is_file()


# ------------------------------------------------------------------ time estimate
class _Recorded(tqdm):
    """tqdm that keeps every bar made."""

    made: ClassVar[list[tqdm]] = []

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.kwargs = kwargs
        _Recorded.made.append(self)


def test_a_long_evaluation_prints_its_estimated_time_and_the_bar_carries_it(
    cli, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Every clock reading 30 s later: one line after the first seed (past the warm-up
    bound, so it is estimated from at once); the bar counts
    the decisions to run, at the run's average rate, with the time left as postfix."""
    readings = iter(range(0, 10_000, 30))
    monkeypatch.setattr(
        eval_cli, "TimeEstimate", functools.partial(TimeEstimate, clock=readings.__next__)
    )
    monkeypatch.setattr(eval_cli, "tqdm", _Recorded)
    # As on a terminal: the bar is drawn only there.
    monkeypatch.setattr(eval_cli, "progress_shown", lambda requested, stream=None: requested)
    _Recorded.made.clear()
    out = tmp_path / "res.json"
    args = ["sim.num_tasks=30", "policy=[mpdm,rbts]", "seeds=[0,1,2,3,4]", f"output={out}"]
    result = cli("eval", *args)
    assert result.code == 0, result.err
    # A progress note: on stderr, out of the report (stdout, results.txt).
    lines = [line for line in result.err.splitlines() if line.startswith("estimated time")]
    assert "estimated time" not in result.out
    assert lines == ["estimated time: 2.5 min in all, 2.0 min left (30 s per seed, 5 seeds to run)"]
    (bar,) = _Recorded.made
    assert (bar.total, bar.n, bar.kwargs["smoothing"]) == (10 * 30, 10 * 30, 0)
    assert bar.postfix == "~0 s left"
    # Resumed with two of the ten episodes to run: the bar counts only those.
    lines = journal_path(out).read_text().splitlines(keepends=True)
    journal_path(out).write_text("".join(lines[:-2]))
    assert cli("eval", *args, "resume=true").code == 0
    assert (_Recorded.made[-1].total, _Recorded.made[-1].n) == (2 * 30, 2 * 30)


def test_a_short_evaluation_prints_no_estimate(cli, tmp_path: Path) -> None:
    result = cli("eval", *QUICK, "policy=[mpdm]", "seeds=[0,1,2]", f"output={tmp_path / 'r.json'}")
    assert result.code == 0, result.err
    assert "estimated time" not in result.out + result.err
