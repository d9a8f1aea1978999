"""rtaw-results: a real rtaw-eval sweep combined into one table, CSV, JSON and plot; bad
input is one error line and exit status 2."""

from __future__ import annotations

import csv
import json
import os
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import pytest

from rtaw_marl.evaluation import combine_output
from rtaw_marl.evaluation.combine_output import OUTPUT_NAMES
from rtaw_marl.utils.runs import LOCK_NAME, claim_folder
from rtaw_marl.utils.signals import Interrupted

pytestmark = pytest.mark.integration

RTAW_RESULTS = Path(sys.executable).with_name("rtaw-results")

TINY = ["sim.num_tasks=20", "policy=[mpdm,rbts]", "seeds=[0,1]", "progress=false"]

#: Every file rtaw-results writes, sorted.
ALL_FILES = sorted(OUTPUT_NAMES.values())
#: How its stop lines name them.
OUTPUTS = "combined.{txt,csv,json,png} and combined_episodes.csv"


@pytest.fixture
def sweep(cli, tmp_path: Path) -> Path:
    """A two-job rtaw-eval sweep over the fleet size (3 and 5 robots)."""
    folder = tmp_path / "sweep"
    result = cli("eval", "-m", *TINY, "sim.num_robots=3,5", f"hydra.sweep.dir={folder}")
    assert result.code == 0, result.err
    return folder


def _cells(line: str) -> list[str]:
    return [c.strip() for c in line.strip().strip("|").split("|")]


def _table_rows(text: str) -> dict[str, list[str]]:
    """A markdown table's body rows by their first cells joined (setting + policy)."""
    lines = [ln for ln in text.splitlines() if ln.startswith("| ") and not ln.startswith("|---")]
    return {" ".join(_cells(ln)[:2]): _cells(ln) for ln in lines[1:]}


def test_a_sweep_is_combined_into_the_jobs_own_numbers(cli, sweep: Path) -> None:
    result = cli("results", str(sweep))
    assert result.code == 0, result.err
    combined = json.loads((sweep / "combined.json").read_text())
    assert combined["swept"] == ["sim.num_robots"]
    rows = {(r["setting"]["sim.num_robots"], r["policy"]): r for r in combined["rows"]}
    assert set(rows) == {("3", "mpdm"), ("3", "rbts"), ("5", "mpdm"), ("5", "rbts")}
    printed = _table_rows(result.out)
    assert (sweep / "combined.txt").read_text() == result.out.split("combined 2 results")[0]
    for job in ("0", "1"):
        data = json.loads((sweep / job / "results.json").read_text())
        robots = str(data["config"]["sim"]["num_robots"])
        own = {_cells(ln)[0]: _cells(ln) for ln in (sweep / job / "results.txt").read_text()
               .splitlines() if ln.startswith(("| mpdm", "| rbts"))}  # fmt: skip
        for policy in ("mpdm", "rbts"):
            row = rows[(robots, policy)]
            assert row["ttd"] == data["policies"][policy]["ttd"]
            assert row["seeds"] == data["seeds"] == [0, 1]
            assert row["vs"] == data["comparisons"][policy]["vs"]
            # The printed TTD and vs MPDM cells are rtaw-eval's own for that job.
            line = printed[f"{robots} {policy}"]
            assert line[3] == own[policy][1]
            assert line[4] == own[policy][5]
    with (sweep / "combined.csv").open() as fh:
        table = list(csv.DictReader(fh))
    assert [(r["sim.num_robots"], r["policy"]) for r in table] == [
        ("3", "mpdm"), ("3", "rbts"), ("5", "mpdm"), ("5", "rbts")
    ]  # fmt: skip
    for r in table:
        row = rows[(r["sim.num_robots"], r["policy"])]
        assert float(r["ttd_mean"]) == pytest.approx(sum(row["ttd"]) / 2)
        pct = row["vs"].get("mpdm", {}).get("pct")
        assert r["vs_mpdm_pct"] == ("" if pct is None else str(pct))
    assert (sweep / "combined.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert not list(sweep.glob(".*tmp"))


def test_a_sweep_over_policies_merges_into_one_setting(cli, tmp_path: Path, sweep: Path) -> None:
    """Jobs that ran one policy each at the same setting are paired with each other;
    the numbers are those of the job that ran both."""
    folder = tmp_path / "by_policy"
    args = ["sim.num_tasks=20", "sim.num_robots=3", "seeds=[0,1]", "progress=false"]
    result = cli("eval", "-m", *args, "policy=[mpdm],[rbts]", f"hydra.sweep.dir={folder}")
    assert result.code == 0, result.err
    out = tmp_path / "out"
    result = cli("results", str(folder), "--output", str(out))
    assert result.code == 0, result.err
    combined = json.loads((out / "combined.json").read_text())
    assert combined["swept"] == []
    both = json.loads((sweep / "0" / "results.json").read_text())
    (rbts,) = [r for r in combined["rows"] if r["policy"] == "rbts"]
    assert rbts["ttd"] == both["policies"]["rbts"]["ttd"]
    assert rbts["vs"] == both["comparisons"]["rbts"]["vs"]


def test_several_sweeps_with_an_output_folder(cli, tmp_path: Path, sweep: Path) -> None:
    result = cli("results", str(sweep / "0"), str(sweep / "1" / "results.json"))
    assert result.code == 2
    assert result.err.strip() == (
        "error: give --output FOLDER when combining files or several folders"
    )
    out = tmp_path / "both"
    result = cli("results", str(sweep / "0"), str(sweep / "1" / "results.json"),
                 "--output", str(out), "--reference", "rbts")  # fmt: skip
    assert result.code == 0, result.err
    assert "TTD vs RBTS" in result.out.splitlines()[0]
    assert sorted(p.name for p in out.iterdir()) == ALL_FILES


def _job(folder: Path, payload: object, overrides: list[str] | None = None) -> Path:
    folder.mkdir(parents=True)
    (folder / "results.json").write_text(json.dumps(payload))
    if overrides is not None:
        (folder / ".hydra").mkdir()
        (folder / ".hydra" / "overrides.yaml").write_text(
            "".join(f"- {item}\n" for item in overrides)
        )
    return folder / "results.json"


def _nested(depth: int) -> dict:
    """``{"a": {"a": ... {}}}``, ``depth`` objects deep (built without recursion)."""
    inner: dict = {}
    for _ in range(depth - 1):
        inner = {"a": inner}
    return inner


def _payload(
    robots: int, seeds: list[int], ttd: dict[str, list[float]], group: str = "sim"
) -> dict:
    """A results file's contents; ``group="env"``: as written before ``sim`` was ``env``."""
    return {
        "config": {group: {"num_robots": robots}, "policy": list(ttd), "seeds": seeds},
        "seeds": seeds,
        "policies": {name: {"ttd": values} for name, values in ttd.items()},
    }


@pytest.mark.parametrize(
    ("jobs", "message"),
    [
        ({}, "error: no results.json under {root} (rtaw-eval -m writes one per job)"),
        ({"0": "{"}, "error: {root}/0/results.json: cannot be read as JSON"),
        ({"0": {"rows": []}},
         "error: {root}/0/results.json: not an rtaw-eval results file (config, seeds, policies)"),
        ({"0": _payload(3, [0, 1], {"mpdm": [1.0]})},
         "error: {root}/0/results.json: policy mpdm has no TTD per seed (2 seeds)"),
        ({"0": _payload(3, [0, 1], {"mpdm": [1.0, 2.0]}),
          "1": _payload(3, [0, 1], {"mpdm": [1.0, 3.0]})},
         "error: the setting: policy mpdm is in {root}/0/results.json and {root}/1/results.json"),
        ({"0": _payload(3, [0, 1], {"mpdm": [1.0, 2.0]}),
          "1": _payload(3, [0, 2], {"rbts": [1.0, 3.0]})},
         "error: the setting: {root}/0/results.json has seeds [0, 1], {root}/1/results.json "
         "[0, 2]; paired comparisons need the same seeds"),
        # rtaw-eval refuses a seed listed twice: it would narrow every interval.
        ({"0": _payload(3, [0, 0], {"mpdm": [1.0, 1.0]})},
         "error: {root}/0/results.json: seeds lists a seed more than once: 0 (2 times); "
         "each seed is one episode, list it once"),
        ({"0": _payload(3, [0, -1], {"mpdm": [1.0, 1.0]})},
         "error: {root}/0/results.json: seeds[1] must be an integer >= 0, got -1"),
        ({"0": {**_payload(3, [0], {"mpdm": [1.0]}), "config": [1]}},
         "error: {root}/0/results.json: config is a list, not an object"),
        ({"0": {**_payload(3, [0], {"mpdm": [1.0]}),
                "policies": {"mpdm": {"ttd": [1.0], "makespan": [1.0, 2.0]}}}},
         "error: {root}/0/results.json: policy mpdm: metric makespan is not one number (or "
         "null) per seed (1 seeds)"),
        ({"0": {**_payload(3, [0], {"mpdm": [1.0]}), "lower_bound": [1.0, 2.0]}},
         "error: {root}/0/results.json: lower_bound is not null or one number per seed"),
        ({"0": '{"config": {}, "seeds": [0], "policies": {"mpdm": {"ttd": [NaN]}}}'},
         "error: {root}/0/results.json: cannot be read as JSON (NaN is not strict JSON)"),
        # Too deep for Python's JSON parser (a RecursionError inside it) ...
        ({"0": '{"config": ' + "[" * 200_000 + "]" * 200_000 + "}"},
         "error: {root}/0/results.json: nested more than 32 levels deep; not an rtaw-eval "
         "results file"),
        # ... and parsed, but too deep for what reads it next (the config's flattening).
        ({"0": {**_payload(3, [0], {"mpdm": [1.0]}), "config": _nested(500)}},
         "error: {root}/0/results.json: nested more than 32 levels deep"),
    ],
    ids=["none", "not-json", "foreign", "short-ttd", "same-policy", "other-seeds",
         "duplicate-seeds", "negative-seed", "config-list", "short-metric", "bound",
         "nan", "deep-parse", "deep-config"],
)  # fmt: skip
def test_bad_input_is_one_line_and_status_2(cli, tmp_path: Path, jobs: dict, message: str) -> None:
    root = tmp_path / "bad"
    root.mkdir()
    for name, payload in jobs.items():
        (root / name).mkdir()
        text = payload if isinstance(payload, str) else json.dumps(payload)
        (root / name / "results.json").write_text(text)
    result = cli("results", str(root))
    assert result.code == 2
    assert result.out == ""
    assert len(result.err.splitlines()) == 1
    assert result.err.startswith(message.format(root=root.resolve() if jobs else root))
    assert not list(root.glob("combined.*"))


def test_settings_are_named_by_the_overrides_that_differ(cli, tmp_path: Path) -> None:
    """Jobs named by their overrides file; a baseline asked for that no job ran is
    refused with the list of those that did."""
    root = tmp_path / "s"
    _job(root / "0", _payload(3, [0], {"mpdm": [2.0], "rbts": [1.0]}),
         ["sim.num_robots=3", "seeds=[0]", "+policy=[mpdm,rbts]"])  # fmt: skip
    _job(root / "1", _payload(5, [0], {"mpdm": [4.0], "rbts": [3.0]}),
         ["sim.num_robots=5", "seeds=[0]", "+policy=[mpdm,rbts]"])  # fmt: skip
    result = cli("results", str(root))
    assert result.code == 0, result.err
    assert _table_rows(result.out)["5 rbts"] == ["5", "rbts", "1", "3.00", "+25.0% [n/a]"]
    result = cli("results", str(root), "--reference", "lookahead")
    assert result.code == 2
    assert (
        result.err
        == "error: --reference lookahead was evaluated in no job; evaluated: mpdm, rbts\n"
    )
    result = cli("results", str(root), "--compare-to", "hungarian")
    assert result.code == 2
    assert "evaluated: mpdm, rbts" in result.err


@pytest.mark.parametrize("old", [{"0", "1"}, {"0"}], ids=["both-old", "one-old"])
def test_results_written_before_sim_was_env_still_combine(
    cli, tmp_path: Path, old: set[str]
) -> None:
    """Results files (``config.env``) and overrides (``env.num_robots=3``) written before
    the simulator's group was renamed ``sim`` are read under today's names: alone or
    beside new ones they give the numbers and setting names new files give."""
    tables = {}
    for spelling in ("new", "mixed"):
        root = tmp_path / spelling
        for job, robots, ttd in (("0", 3, [2.0, 1.0]), ("1", 5, [4.0, 3.0])):
            group = "env" if spelling == "mixed" and job in old else "sim"
            _job(root / job, _payload(robots, [0], {"mpdm": ttd[:1], "rbts": ttd[1:]}, group),
                 [f"{group}.num_robots={robots}", "seeds=[0]", "+policy=[mpdm,rbts]"])  # fmt: skip
        result = cli("results", str(root))
        assert result.code == 0, result.err
        combined = json.loads((root / "combined.json").read_text())
        assert combined["swept"] == ["sim.num_robots"]
        rows = [{k: v for k, v in r.items() if k != "source"} for r in combined["rows"]]
        tables[spelling] = (result.out.split("combined 2 results")[0], rows)
    assert tables["mixed"] == tables["new"]
    for folder in ("0", "1"):  # read, never rewritten
        written = json.loads((tmp_path / "mixed" / folder / "results.json").read_text())
        assert next(iter(written["config"])) == ("env" if folder in old else "sim")


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("5\n", "not a Hydra overrides list (a list of KEY=VALUE strings"),
        ("- sim.num_robots=3\n- {a: 1}\n", "not a Hydra overrides list"),
        ("- [unclosed\n", "cannot be read ("),
        ("[" * 200_000 + "]" * 200_000, "nested too deeply to be a Hydra overrides list"),
    ],
    ids=["a-number", "not-strings", "bad-yaml", "deep"],
)
def test_a_bad_overrides_file_is_one_line_naming_it(
    cli, tmp_path: Path, text: str, message: str
) -> None:
    root = tmp_path / "s"
    _job(root / "0", _payload(3, [0], {"mpdm": [2.0]}), [])
    overrides = root / "0" / ".hydra" / "overrides.yaml"
    overrides.write_text(text)
    result = cli("results", str(root))
    assert result.code == 2
    assert result.out == ""
    assert result.err.startswith(f"error: {overrides.resolve()}: {message}")
    assert len(result.err.splitlines()) == 1
    assert not list(root.glob("combined.*"))


@pytest.mark.parametrize("through", ["the-folder", "a-symlinked-folder", "a-relative-path"])
def test_an_output_that_is_an_input_is_refused_before_any_work(
    cli, tmp_path: Path, through: str
) -> None:
    """``rtaw-results DIR/combined.json --output DIR`` would replace its own input."""
    folder = tmp_path / "d"
    folder.mkdir()
    given = folder / "combined.json"
    given.write_text(json.dumps(_payload(3, [0, 1], {"mpdm": [1.0, 2.0]})))
    before = given.read_bytes()
    output = {"the-folder": str(folder), "a-symlinked-folder": "link",
              "a-relative-path": "d/../d/"}[through]  # fmt: skip
    (tmp_path / "link").symlink_to(folder)
    result = cli("results", str(given), "--output", output)
    assert result.code == 2
    assert result.out == ""
    assert result.err == (
        f"error: --output {Path(output)}: combined.json would overwrite the input "
        f"{given}; choose another --output folder\n"
    )
    assert given.read_bytes() == before
    assert sorted(p.name for p in folder.iterdir()) == ["combined.json"]  # no lock either


def test_the_output_folder_is_held_while_the_files_are_written(cli, tmp_path: Path) -> None:
    root = tmp_path / "s"
    _job(root / "0", _payload(3, [0], {"mpdm": [2.0], "rbts": [1.0]}))
    out = tmp_path / "out"
    with claim_folder(out):
        result = cli("results", str(root), "--output", str(out))
        assert result.code == 2
        assert result.err == (
            f"error: --output={out} is in use by another running process (pid {os.getpid()}); "
            "choose another one\n"
        )
        assert not list(out.glob("combined.*"))
    result = cli("results", str(root), "--output", str(out))
    assert result.code == 0, result.err
    # The lock is gone once the run ends; the five files are there.
    assert sorted(p.name for p in out.iterdir()) == ALL_FILES


# ------------------------------------------------------------------ stops
def _old_set(out: Path) -> dict[str, bytes]:
    """A previous run's combined files (made-up contents)."""
    out.mkdir()
    old = {}
    for name in OUTPUT_NAMES.values():
        path = out / name
        path.write_bytes(f"old {name}".encode())
        old[path.name] = path.read_bytes()
    return old


def _contents(out: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(out.iterdir())}


@pytest.mark.parametrize(
    ("stop", "status"),
    [(KeyboardInterrupt(), 130), (Interrupted(signum=signal.SIGTERM), 143)],
    ids=["ctrl-c", "sigterm"],
)
def test_a_stop_while_writing_leaves_the_previous_set(
    cli, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, stop: KeyboardInterrupt, status: int
) -> None:
    """Stopped after two of the five new files are on disk (as temporaries): the old
    set is left whole, no temporary or lock is left, one line, 128 + signal."""
    root = tmp_path / "s"
    _job(root / "0", _payload(3, [0, 1], {"mpdm": [2.0, 3.0], "rbts": [1.0, 2.0]}))
    out = tmp_path / "out"
    old = _old_set(out)
    temporary, calls = combine_output._temporary, []

    def stopping(path: Path, data: bytes) -> Path:
        calls.append(path.name)
        if len(calls) == 3:
            raise stop
        return temporary(path, data)

    monkeypatch.setattr(combine_output, "_temporary", stopping)
    result = cli("results", str(root), "--output", str(out))
    assert result.code == status
    assert result.err == f"interrupted: nothing written; any {OUTPUTS} in {out} are as they were\n"
    assert _contents(out) == old  # no temporary, no lock, the old files as they were


def test_a_signal_while_renaming_lets_the_whole_set_in(
    cli, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A real SIGTERM that arrives while the files are renamed in waits until all five
    are in: the line says so, exit 143."""
    root = tmp_path / "s"
    _job(root / "0", _payload(3, [0, 1], {"mpdm": [2.0, 3.0], "rbts": [1.0, 2.0]}))
    out = tmp_path / "out"
    old = _old_set(out)
    deferred = combine_output.signals_held

    @contextmanager
    def signalled() -> Iterator[None]:
        with deferred():
            os.kill(os.getpid(), signal.SIGTERM)  # handled once the block ends
            yield

    monkeypatch.setattr(combine_output, "signals_held", signalled)
    result = cli("results", str(root), "--output", str(out))
    assert result.code == 143
    assert result.err == f"interrupted: {OUTPUTS} were all written to {out}\n"
    new = _contents(out)
    assert sorted(new) == sorted(old)
    assert all(new[name] != old[name] for name in old)
    assert json.loads(new["combined.json"])["rows"][0]["policy"] == "mpdm"


@pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals")
def test_sigterm_during_a_long_combine_writes_nothing(tmp_path: Path) -> None:
    """A real SIGTERM to the console script while it combines and plots 300 jobs (it
    holds its output folder by then): one line, exit 143, no combined file and no lock
    left."""
    root = tmp_path / "sweep"
    for i in range(300):
        _job(root / str(i), _payload(i + 1, [0, 1], {"mpdm": [2.0 + i, 3.0], "rbts": [1.0, 2.0]}))
    out = tmp_path / "out"
    proc = subprocess.Popen(
        [str(RTAW_RESULTS), str(root), "--output", str(out)],
        stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    try:
        # The lock is taken inside the SIGTERM handler's block, once the files are read
        # and before the seconds of plotting 300 settings.
        deadline = time.monotonic() + 60
        while proc.poll() is None and not (out / LOCK_NAME).exists():
            assert time.monotonic() < deadline, "rtaw-results never took its output folder"
            time.sleep(0.01)
        proc.send_signal(signal.SIGTERM)
        _, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 143, err
    assert err == f"interrupted: nothing written; any {OUTPUTS} in {out} are as they were\n"
    assert list(out.iterdir()) == []
