"""rtaw-results --metric: the table, CSV and JSON of any metric the results hold, signed
by which way it is better; an unknown one is one error line, nothing written; and the
per-episode table of every metric, one row per job, policy and seed."""

from __future__ import annotations

import csv
import io
import json
from pathlib import Path

import pytest

from rtaw_marl.evaluation.metric_goals import metric_difference

pytestmark = pytest.mark.integration

SEEDS = [0, 1, 2]
POLICIES = ("mpdm", "rbts", "lookahead")
METRICS = ("ttd", "makespan", "tasks_finished", "wait_mean")


def _value(metric: int, robots: int, layout: int, policy: int, seed: int) -> float:
    """Made-up values, each (metric, setting, policy, seed) its own number."""
    return 1000.0 * (metric + 1) + 10.0 * robots + 100 * layout + 3.0 * policy * (seed + 1) + seed


def _sweep(root: Path) -> dict[tuple[str, str], dict]:
    """Four jobs: 3 and 5 robots x layouts A and C, three policies, three seeds; the
    results files' contents by (robots, layout)."""
    written = {}
    for i, (robots, layout) in enumerate((r, lay) for r in (3, 5) for lay in (0, 1)):
        name = "AC"[layout]
        job = root / str(i)
        (job / ".hydra").mkdir(parents=True)
        overrides = [f"sim.num_robots={robots}", f"layout={name}", "seeds=[0,1,2]"]
        (job / ".hydra" / "overrides.yaml").write_text("".join(f"- {o}\n" for o in overrides))
        policies = {
            p: {m: [_value(k, robots, layout, j, s) for s in SEEDS] for k, m in enumerate(METRICS)}
            for j, p in enumerate(POLICIES)
        }
        config = {"sim": {"num_robots": robots}, "layout": {"name": name}, "seeds": SEEDS}
        payload = {"config": config, "seeds": SEEDS, "policies": policies}
        (job / "results.json").write_text(json.dumps(payload))
        written[(str(robots), name)] = payload
    return written


@pytest.mark.parametrize("metric", ["makespan", "tasks_finished", "wait_mean"])
def test_the_metric_is_the_one_in_the_files(cli, tmp_path: Path, metric: str) -> None:
    root = tmp_path / "sweep"
    written = _sweep(root)
    result = cli("results", str(root), "--metric", metric, "--compare-to", "rbts")
    assert result.code == 0, result.err
    head = result.out.splitlines()[0]
    assert f"| {metric} ± 95% CI | {metric} vs MPDM | {metric} vs RBTS |" in head
    combined = json.loads((root / "combined.json").read_text())
    assert (combined["metric"], combined["swept"]) == (metric, ["sim.num_robots", "layout"])
    assert combined["goal"] == {"makespan": "lower", "tasks_finished": "higher"}.get(
        metric, "lower"
    )
    assert len(combined["rows"]) == 4 * 3
    for row in combined["rows"]:
        source = written[(row["setting"]["sim.num_robots"], row["setting"]["layout"])]
        values = source["policies"][row["policy"]][metric]
        assert row[metric] == values
        assert row[f"{metric}_mean"] == pytest.approx(sum(values) / 3)
        assert "ttd" not in row
        for base in ("mpdm", "rbts"):
            if base != row["policy"]:
                expected = metric_difference(metric, source["policies"][base][metric], values)
                assert row["vs"][base] == expected.as_dict()
    with (root / "combined.csv").open() as fh:
        lines = list(csv.DictReader(fh))
    assert float(lines[0][f"{metric}_mean"]) == pytest.approx(combined["rows"][0][f"{metric}_mean"])


def test_the_sign_follows_the_metrics_goal(cli, tmp_path: Path) -> None:
    """lookahead has more of every metric than MPDM: worse makespan (-), more tasks
    finished (+, better)."""
    root = tmp_path / "sweep"
    _sweep(root)
    for metric, sign in (("makespan", -1), ("tasks_finished", 1)):
        assert cli("results", str(root), "--metric", metric).code == 0
        rows = json.loads((root / "combined.json").read_text())["rows"]
        pct = [r["vs"]["mpdm"]["pct"] for r in rows if r["policy"] == "lookahead"]
        assert len(pct) == 4
        assert all(sign * p > 0 for p in pct)
    assert "tasks_finished above X's" in (root / "combined.txt").read_text()


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--metric", "makespn"],
         "error: --metric makespn: unknown metric; valid: ttd, makespan, tasks_finished, "
         "wait_mean; did you mean 'makespan'?"),
        (["--metric", "planning_calls"],
         "error: --metric planning_calls: held only by some results ({root}/0/results.json "
         "(mpdm) ...), not all; valid: ttd, makespan, tasks_finished, wait_mean"),
        (["--metric", "wait_mean"],
         "error: --metric wait_mean: {root}/1/results.json: policy rbts has no finite "
         "wait_mean on seed 2 (null); compare another metric"),
    ],
    ids=["unknown", "in-some", "null"],
)  # fmt: skip
def test_a_metric_not_in_every_result_is_one_line_and_nothing_written(
    cli, tmp_path: Path, args: list[str], message: str
) -> None:
    root = tmp_path / "sweep"
    _sweep(root)
    for job, change in (("0", ("mpdm", "planning_calls", [1.0] * 3)),
                        ("1", ("rbts", "wait_mean", [1.0, 2.0, None]))):  # fmt: skip
        path = root / job / "results.json"
        data = json.loads(path.read_text())
        data["policies"][change[0]][change[1]] = change[2]
        path.write_text(json.dumps(data))
    out = tmp_path / "out"
    result = cli("results", str(root), "--output", str(out), *args)
    assert result.code == 2
    assert result.out == ""
    assert result.err == message.format(root=root.resolve()) + "\n"
    assert not out.exists()  # no folder, no lock, no file


def test_an_x_that_is_not_swept_is_one_line(cli, tmp_path: Path) -> None:
    root = tmp_path / "sweep"
    _sweep(root)
    result = cli("results", str(root), "--x", "navigator")
    assert result.code == 2
    assert result.err == "error: --x navigator is not a swept key; swept: sim.num_robots, layout\n"
    assert not list(root.glob("combined*"))
    assert cli("results", str(root), "--x", "layout").code == 0


def test_the_episode_table_is_every_metric_of_every_job_policy_and_seed(
    cli, tmp_path: Path
) -> None:
    root = tmp_path / "sweep"
    written = _sweep(root)
    result = cli("results", str(root), "--metric", "makespan")
    assert result.code == 0, result.err
    assert "combined_episodes.csv" in result.out.splitlines()[-1]
    text = (root / "combined_episodes.csv").read_text()
    lines = list(csv.DictReader(io.StringIO(text)))
    assert text.splitlines()[0] == (
        "sim.num_robots,layout,policy,seed,ttd,makespan,tasks_finished,wait_mean,source"
    )
    assert len(lines) == 4 * len(POLICIES) * len(SEEDS)  # jobs x policies x seeds
    seen = set()
    for line in lines:
        source = written[(line["sim.num_robots"], line["layout"])]
        i = SEEDS.index(int(line["seed"]))
        for metric in METRICS:
            assert float(line[metric]) == source["policies"][line["policy"]][metric][i]
        assert json.loads(Path(line["source"]).read_text()) == source
        seen.add((line["sim.num_robots"], line["layout"], line["policy"], line["seed"]))
    assert len(seen) == len(lines)
