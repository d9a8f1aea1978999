"""rtaw-results: a real rtaw-eval sweep combined into one table, CSV, JSON and plot; bad
input is one error line and exit status 2."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import pytest

pytestmark = pytest.mark.integration

TINY = ["env.num_tasks=20", "policy=[mpdm,rbts]", "seeds=[0,1]", "progress=false"]


@pytest.fixture
def sweep(cli, tmp_path: Path) -> Path:
    """A two-job rtaw-eval sweep over the fleet size (3 and 5 robots)."""
    folder = tmp_path / "sweep"
    result = cli("eval", "-m", *TINY, "env.num_robots=3,5", f"hydra.sweep.dir={folder}")
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
    assert combined["swept"] == ["env.num_robots"]
    rows = {(r["setting"]["env.num_robots"], r["policy"]): r for r in combined["rows"]}
    assert set(rows) == {("3", "mpdm"), ("3", "rbts"), ("5", "mpdm"), ("5", "rbts")}
    printed = _table_rows(result.out)
    assert (sweep / "combined.txt").read_text() == result.out.split("combined 2 results")[0]
    for job in ("0", "1"):
        data = json.loads((sweep / job / "results.json").read_text())
        robots = str(data["config"]["env"]["num_robots"])
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
    assert [(r["env.num_robots"], r["policy"]) for r in table] == [
        ("3", "mpdm"), ("3", "rbts"), ("5", "mpdm"), ("5", "rbts")
    ]  # fmt: skip
    for r in table:
        row = rows[(r["env.num_robots"], r["policy"])]
        assert float(r["ttd_mean"]) == pytest.approx(sum(row["ttd"]) / 2)
        pct = row["vs"].get("mpdm", {}).get("pct")
        assert r["vs_mpdm_pct"] == ("" if pct is None else str(pct))
    assert (sweep / "combined.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert not list(sweep.glob(".*tmp"))


def test_a_sweep_over_policies_merges_into_one_setting(cli, tmp_path: Path, sweep: Path) -> None:
    """Jobs that ran one policy each at the same setting are paired with each other;
    the numbers are those of the job that ran both."""
    folder = tmp_path / "by_policy"
    args = ["env.num_tasks=20", "env.num_robots=3", "seeds=[0,1]", "progress=false"]
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
    assert sorted(p.name for p in out.iterdir()) == [
        "combined.csv", "combined.json", "combined.png", "combined.txt"
    ]  # fmt: skip


def _job(folder: Path, payload: object, overrides: list[str] | None = None) -> Path:
    folder.mkdir(parents=True)
    (folder / "results.json").write_text(json.dumps(payload))
    if overrides is not None:
        (folder / ".hydra").mkdir()
        (folder / ".hydra" / "overrides.yaml").write_text(
            "".join(f"- {item}\n" for item in overrides)
        )
    return folder / "results.json"


def _payload(robots: int, seeds: list[int], ttd: dict[str, list[float]]) -> dict:
    return {
        "config": {"env": {"num_robots": robots}, "policy": list(ttd), "seeds": seeds},
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
    ],
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
         ["env.num_robots=3", "seeds=[0]", "+policy=[mpdm,rbts]"])  # fmt: skip
    _job(root / "1", _payload(5, [0], {"mpdm": [4.0], "rbts": [3.0]}),
         ["env.num_robots=5", "seeds=[0]", "+policy=[mpdm,rbts]"])  # fmt: skip
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
