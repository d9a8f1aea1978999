"""Nothing is lost or mixed up: unique and exclusive run folders, outputs checked before
the work, sweeps that survive a failed job, evaluations that survive a kill."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from rtaw_marl.errors import ConfigError
from rtaw_marl.evaluation import evaluate
from rtaw_marl.evaluation.journal import EpisodeJournal, journal_path
from rtaw_marl.policies import MPDM
from rtaw_marl.sim.builder import SimSpec, build_sim
from rtaw_marl.utils import runs
from rtaw_marl.utils.runs import LOCK_NAME, check_writable_file, claim_file, claim_folder

pytestmark = pytest.mark.integration

QUICK = ("sim.num_tasks=30", "progress=false", "policy=[mpdm,rbts]")


@pytest.fixture
def holder(tmp_path: Path):
    """``holder(lock_file)``: another process holds ``lock_file`` until the test ends."""
    procs: list[subprocess.Popen[str]] = []

    def hold(lock: Path) -> None:
        lock.parent.mkdir(parents=True, exist_ok=True)
        code = (
            "import fcntl, sys, time\n"
            f"f = open({str(lock)!r}, 'a+'); fcntl.flock(f, fcntl.LOCK_EX)\n"
            "f.write('4242'); f.flush(); print('held', flush=True); time.sleep(60)\n"
        )
        proc = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True)
        procs.append(proc)
        assert proc.stdout is not None
        assert proc.stdout.readline().strip() == "held"

    yield hold
    for proc in procs:
        proc.kill()
        proc.wait()


# --------------------------------------------------------------------------- folders
def test_two_runs_in_the_same_second_get_their_own_folders(cli) -> None:
    first = cli("eval", *QUICK, "seeds=[0]")
    second = cli("eval", *QUICK, "seeds=[0]")
    assert first.code == second.code == 0, first.err + second.err
    paths = [r.out.split("results: ")[-1].splitlines()[0] for r in (first, second)]
    assert paths[0] != paths[1]
    assert all(Path(p).is_file() for p in paths)
    assert f"_{os.getpid()}" in paths[0]


@pytest.mark.skipif(sys.platform == "win32", reason="flock is POSIX")
def test_a_held_folder_is_refused(tmp_path: Path, holder) -> None:
    holder(tmp_path / "run" / LOCK_NAME)
    with (
        pytest.raises(ConfigError, match=r"output_dir=.*run is in use .*pid 4242"),
        claim_folder(tmp_path / "run"),
    ):
        pass


def test_a_folder_is_free_again_after_its_run(tmp_path: Path) -> None:
    with claim_folder(tmp_path / "run"):
        assert (tmp_path / "run" / LOCK_NAME).is_file()
    assert not (tmp_path / "run" / LOCK_NAME).exists()  # no lock file left behind
    with claim_folder(tmp_path / "run") as folder:
        assert folder == tmp_path / "run"


def test_no_lock_file_is_left_after_a_run_or_its_error(tmp_path: Path) -> None:
    out = tmp_path / "res.json"
    with claim_file(out):
        out.write_text("{}")
    with pytest.raises(RuntimeError, match="boom"), claim_file(out):
        raise RuntimeError("boom")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["res.json"]


@pytest.mark.skipif(sys.platform == "win32", reason="flock is POSIX")
def test_a_lock_file_deleted_by_its_holder_is_not_taken(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A lock file opened just before its holder deleted it is stale: the claim locks the
    file on disk instead, so a third run cannot take a second lock beside it."""
    lock_path = tmp_path / ".res.json.lock"
    real_open = runs._open_lock
    opened: list[int] = []

    def open_then_lose(path: Path, name: str, kept: str):
        handle = real_open(path, name, kept)
        if not opened:
            path.unlink()  # the holder ended between our open and our flock
        opened.append(os.fstat(handle.fileno()).st_ino)
        return handle

    monkeypatch.setattr(runs, "_open_lock", open_then_lose)
    with claim_file(tmp_path / "res.json"):
        assert len(opened) == 2
        assert os.stat(lock_path).st_ino == opened[1]
    assert not lock_path.exists()


@pytest.mark.skipif(sys.platform == "win32", reason="flock is POSIX")
def test_two_trainings_cannot_share_a_folder(cli, tmp_path: Path, holder) -> None:
    holder(tmp_path / "run" / LOCK_NAME)
    result = cli("train", "scenario=poc", f"output_dir={tmp_path / 'run'}", "progress=false")
    assert result.code == 2
    assert "is in use by another running process" in result.err
    assert not (tmp_path / "run" / "checkpoints").exists()


@pytest.mark.skipif(sys.platform == "win32", reason="flock is POSIX")
def test_two_evaluations_cannot_write_one_output(cli, tmp_path: Path, holder) -> None:
    out = tmp_path / "res.json"
    holder(tmp_path / ".res.json.lock")
    result = cli("eval", *QUICK, f"output={out}")
    assert result.code == 2
    assert f"output={out} is in use" in result.err
    # Another file of the same folder is not blocked.
    assert cli("eval", *QUICK, "seeds=[0]", f"output={tmp_path / 'other.json'}").code == 0


# --------------------------------------------------------------------------- outputs
def _unwritable(tmp_path: Path) -> dict[str, tuple[str, str]]:
    (tmp_path / "afile").write_text("x")
    (tmp_path / "adir").mkdir()
    return {
        "under a file": (str(tmp_path / "afile" / "results.json"), "cannot be written"),
        "a folder": (str(tmp_path / "adir"), "is a folder; name a file"),
        "in /proc": ("/proc/rtaw/results.json", "cannot be written"),
    }


@pytest.mark.parametrize("case", ["under a file", "a folder", "in /proc"])
def test_unwritable_eval_output_fails_before_the_work(cli, tmp_path: Path, case: str) -> None:
    path, message = _unwritable(tmp_path)[case]
    result = cli("eval", *QUICK, "seeds=[0,1,2,3,4,5,6,7]", f"output={path}")
    assert result.code == 2
    assert message in result.err
    assert len(result.err.strip().splitlines()) == 1
    # Refused before any episode: the layout line is printed after the check.
    assert "layout" not in result.out


@pytest.mark.skipif(os.name != "posix" or os.geteuid() == 0, reason="root writes anywhere")
def test_read_only_output_folder(tmp_path: Path) -> None:
    folder = tmp_path / "ro"
    folder.mkdir()
    folder.chmod(0o500)
    with pytest.raises(ConfigError, match="cannot be written"):
        check_writable_file(folder / "results.json")


@pytest.mark.parametrize(
    ("app", "args"),
    [
        ("train", ("scenario=poc", "output_dir={file}/run", "progress=false")),
        ("train", ("scenario=poc", "output_dir={file}", "progress=false")),
        ("render", ("navigator=sipp", "output={file}/episode.gif")),
    ],
)
def test_unwritable_outputs_of_the_other_clis(cli, tmp_path: Path, app: str, args) -> None:
    afile = tmp_path / "afile"
    afile.write_text("x")
    result = cli(app, *(a.format(file=afile) for a in args))
    assert result.code == 2, result.err
    assert result.err.startswith("error: ")
    assert "afile" in result.err
    assert len(result.err.strip().splitlines()) == 1


# --------------------------------------------------------------------------- sweeps
@pytest.mark.parametrize("launcher", ["basic", "joblib"])
def test_a_failed_job_does_not_stop_the_sweep(cli, tmp_path: Path, launcher: str) -> None:
    result = cli(
        "eval", "--multirun", "sim.num_robots=0,3", *QUICK, "seeds=[0]",
        f"hydra/launcher={launcher}",
    )  # fmt: skip
    assert result.code == 2
    lines = result.err.strip().splitlines()
    assert lines[-1].startswith("error: 1 of 2 jobs failed")
    assert "Traceback" not in result.err
    results = list(tmp_path.glob("multirun/**/results.json"))
    assert [p.parent.name for p in results] == ["1"]
    failed = (results[0].parent.parent / "0" / "FAILED").read_text()
    assert failed.startswith("job 0 (sim.num_robots=0 ")
    assert "sim.num_robots must be >= 1" in failed
    if launcher == "basic":  # joblib's jobs print from other processes, past capsys
        assert lines[0] == f"error: {failed.strip()}"


# --------------------------------------------------------------------------- journal
class _KilledAfter:
    """MPDM that is "killed" (KeyboardInterrupt) when it starts its n-th episode."""

    name = "mpdm"

    def __init__(self, n: int) -> None:
        self.inner, self.left = MPDM(), n

    def reset(self, seed: int | None = None) -> None:
        self.left -= 1
        if self.left == 0:
            raise KeyboardInterrupt
        self.inner.reset(seed)

    def act_sim(self, sim) -> int:
        return self.inner.act_sim(sim)


def test_finished_episodes_survive_a_kill(tmp_path: Path) -> None:
    sim = build_sim(SimSpec.of(sim={"num_tasks": 30}))
    path = tmp_path / "results.episodes.jsonl"
    journal = EpisodeJournal(path, {"a": 1}, resume=False)
    with pytest.raises(KeyboardInterrupt):
        # No warm-up: its untimed decisions would be the policy's first "episode" here.
        evaluate(sim, {"mpdm": _KilledAfter(3)}, [0, 1, 2, 3], journal=journal, warm_up_decisions=0)
    journal.close()
    replay = EpisodeJournal(path, {"a": 1}, resume=True)
    assert sorted(replay.episodes) == [("mpdm", 0), ("mpdm", 1)]
    fresh = evaluate(sim, {"mpdm": MPDM()}, [0, 1])
    assert [replay.get("mpdm", s)["ttd"] for s in (0, 1)] == fresh["mpdm"]["ttd"]


def test_resume_skips_finished_episodes_and_drops_a_torn_line(cli, tmp_path: Path) -> None:
    out = tmp_path / "res.json"
    seeds = "seeds=[0,1,2]"
    assert cli("eval", *QUICK, seeds, f"output={out}").code == 0
    full = json.loads(out.read_text())
    journal = journal_path(out)
    lines = journal.read_text().splitlines(keepends=True)
    assert len(lines) == 1 + 6  # the header, then 2 policies x 3 seeds
    # As if killed while writing the fourth episode.
    journal.write_text("".join(lines[:4]) + lines[4][:20])
    out.unlink()
    result = cli("eval", *QUICK, seeds, f"output={out}", "resume=true")
    assert result.code == 0, result.err
    assert "resume: 3 finished episodes" in result.out
    resumed = json.loads(out.read_text())
    for name in ("mpdm", "rbts"):
        assert resumed["policies"][name]["ttd"] == full["policies"][name]["ttd"]
    # Replayed episodes (seed by seed: mpdm and rbts on seed 0, mpdm on seed 1) keep
    # their recorded wall times: they were not run again.
    for name, n in (("mpdm", 2), ("rbts", 1)):
        replayed = resumed["policies"][name]["wall_time_s"][:n]
        assert replayed == full["policies"][name]["wall_time_s"][:n]
    assert len(journal.read_text().splitlines()) == 7


@pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals")
def test_kill_9_keeps_the_finished_episodes(tmp_path: Path) -> None:
    """A real SIGKILL in the middle of an evaluation: the journal keeps every finished
    episode, and resume=true completes the run from there."""
    out = tmp_path / "res.json"
    args = [str(Path(sys.executable).with_name("rtaw-eval")), "sim.num_tasks=200",
            "policy=[mpdm]", "seeds=${range:0,400}", "progress=false", f"output={out}"]  # fmt: skip
    proc = subprocess.Popen(args, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    journal = journal_path(out)
    try:
        while proc.poll() is None and (not journal.exists() or journal.read_text().count("\n") < 4):
            time.sleep(0.1)
        proc.kill()
        proc.wait()
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == -signal.SIGKILL
    assert not out.exists()
    kept = EpisodeJournal(journal, json.loads(journal.read_text().splitlines()[0])["setting"],
                          resume=True)  # fmt: skip
    kept.close()
    finished = len(kept.episodes)
    assert finished >= 3
    resumed = subprocess.run(
        [*args[:4], "seeds=${range:0,8}", *args[5:], "resume=true"],
        capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    assert resumed.returncode == 0, resumed.stderr
    assert f"resume: {finished} finished episodes" in resumed.stdout
    assert len(json.loads(out.read_text())["policies"]["mpdm"]["ttd"]) == 8


def test_resume_refuses_another_setting(cli, tmp_path: Path) -> None:
    out = tmp_path / "res.json"
    assert cli("eval", *QUICK, "seeds=[0]", f"output={out}").code == 0
    result = cli("eval", *QUICK, "seeds=[0]", f"output={out}", "resume=true", "sim.num_robots=7")
    assert result.code == 2
    assert "holds episodes of another setting (differs in sim.num_robots: 10 -> 7)" in result.err


def test_resume_continues_a_journal_written_before_sim_was_env(cli, tmp_path: Path) -> None:
    """A journal whose setting says ``env`` (written before the simulator's group was
    renamed ``sim``) is the same setting: its episodes are replayed, and a changed key is
    named ``sim.*``."""
    out = tmp_path / "res.json"
    assert cli("eval", *QUICK, "seeds=[0,1]", f"output={out}").code == 0
    journal = journal_path(out)
    header, *episodes = journal.read_text().splitlines()
    old = json.loads(header)
    old["setting"] = {("env" if k == "sim" else k): v for k, v in old["setting"].items()}
    journal.write_text("\n".join([json.dumps(old), *episodes]) + "\n")
    result = cli("eval", *QUICK, "seeds=[0,1,2]", f"output={out}", "resume=true")
    assert result.code == 0, result.err
    assert "resume: 4 finished episodes" in result.out
    assert len(json.loads(out.read_text())["policies"]["mpdm"]["ttd"]) == 3
    journal.write_text("\n".join([json.dumps(old), *episodes]) + "\n")
    result = cli("eval", *QUICK, "seeds=[0]", f"output={out}", "resume=true", "sim.num_robots=7")
    assert result.code == 2
    assert "holds episodes of another setting (differs in sim.num_robots: 10 -> 7)" in result.err


def test_without_resume_the_journal_starts_afresh(cli, tmp_path: Path) -> None:
    out = tmp_path / "res.json"
    assert cli("eval", *QUICK, "seeds=[0,1]", f"output={out}").code == 0
    assert cli("eval", *QUICK, "seeds=[5]", f"output={out}").code == 0
    assert len(journal_path(out).read_text().splitlines()) == 1 + 2


def test_ctrl_c_is_one_line_and_130(cli, monkeypatch: pytest.MonkeyPatch) -> None:
    import rtaw_marl.cli.eval as eval_cli

    def interrupted(*args: object, **kwargs: object) -> None:
        raise KeyboardInterrupt

    monkeypatch.setattr(eval_cli, "evaluate", interrupted)
    result = cli("eval", *QUICK, "seeds=[0]")
    assert result.code == 130
    assert result.err.strip() == "interrupted"


def test_claim_file_checks_before_holding(tmp_path: Path) -> None:
    (tmp_path / "d").mkdir()
    with pytest.raises(ConfigError, match="is a folder"), claim_file(tmp_path / "d"):
        pass
