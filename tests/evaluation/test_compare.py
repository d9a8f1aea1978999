"""compare(): a user's policy or function against the rules, paired, on the same seeds."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pytest

from rtaw_marl.errors import ConfigError
from rtaw_marl.evaluation import compare, evaluate, paired_difference
from rtaw_marl.policies import MPDM, make_baseline
from rtaw_marl.policies.user import CallablePolicy, as_policy
from rtaw_marl.scenarios import SCENARIOS
from rtaw_marl.sim.builder import SimSpec, build_sim

pytestmark = pytest.mark.unit

SMALL = SCENARIOS["C_astar_m10"].with_sim(num_tasks=30)


def first_queued(sim) -> int:
    """A deliberately poor rule: the first queued task, whatever its distance."""
    return int(np.flatnonzero(sim.queue_mask)[0])


def test_a_function_is_compared_with_the_rules_on_the_same_seeds() -> None:
    result = compare(first_queued, SMALL, seeds=[0, 1, 2], against=["mpdm", "hungarian"])
    assert result.label == "first_queued"
    assert list(result.results) == ["first_queued", "mpdm", "hungarian"]
    # The same numbers as evaluate() on the same simulator and seeds.
    sim = build_sim(SMALL.spec())
    policies = {
        "first_queued": CallablePolicy(first_queued),
        "mpdm": make_baseline("mpdm"),
        "hungarian": make_baseline("hungarian"),
    }
    direct = evaluate(sim, policies, [0, 1, 2])
    for label in policies:
        assert result.results[label]["ttd"] == direct[label]["ttd"]
    expected = paired_difference(direct["mpdm"]["ttd"], direct["first_queued"]["ttd"])
    assert result.diffs["mpdm"] == expected
    assert result.diffs["mpdm"].pct < 0  # the first queued task is worse than the nearest
    # The bar is chosen on the selection seeds, not on the reported ones.
    selected = evaluate(sim, {r: policies[r] for r in ("mpdm", "hungarian")}, range(1000, 1020))
    best = min(("mpdm", "hungarian"), key=lambda r: np.mean(selected[r]["ttd"]))
    assert result.best == best
    table = result.table()
    assert "| first_queued |" in table
    assert f"TTD vs {best.upper()}" in table


def test_a_policy_object_and_a_spec_work_too(tmp_path: Path) -> None:
    spec = SimSpec.of(layout="C", navigator="astar", sim={"num_robots": 4, "num_tasks": 12})
    result = compare(MPDM(), spec, seeds=[3, 4], against=["mpdm"], label="my_mpdm")
    # The same rule twice: identical episodes, a difference of exactly 0.
    assert result.results["my_mpdm"]["ttd"] == result.results["mpdm"]["ttd"]
    assert result.diffs["mpdm"].mean == 0.0
    path = result.to_csv(tmp_path / "episodes.csv")
    rows = list(csv.DictReader(path.open()))
    assert [(r["policy"], r["seed"]) for r in rows] == [
        ("my_mpdm", "3"), ("my_mpdm", "4"), ("mpdm", "3"), ("mpdm", "4"),
    ]  # fmt: skip
    assert float(rows[0]["ttd"]) == result.results["my_mpdm"]["ttd"][0]
    assert rows[0].keys() >= {"ttd", "makespan", "wait_max", "wall_time_s"}
    assert result.rows()[1]["seed"] == 4


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"setting": "C_astar_m1O"}, "unknown scenario 'C_astar_m1O'"),
        ({"against": ["mpmd"]}, "unknown policy 'mpmd'"),
        ({"against": []}, "against must name at least one rule"),
        ({"seeds": [0, 0]}, "seeds lists a seed more than once"),
        ({"label": "mpdm"}, "is also a rule's"),
        ({"setting": 3}, "setting must be a scenario name"),
    ],
)
def test_bad_arguments_are_one_clear_error(kwargs: dict, message: str) -> None:
    args = {"setting": SMALL, "seeds": [0], "against": ["mpdm"], **kwargs}
    with pytest.raises(ConfigError, match=message):
        compare(first_queued, **args)


def test_what_is_not_a_policy_is_refused() -> None:
    with pytest.raises(ConfigError, match="expected a policy"):
        as_policy(42, name="answer")

    class NeedsArguments:
        def __init__(self, horizon: int) -> None:
            self.horizon = horizon

    with pytest.raises(ConfigError, match="must build without arguments"):
        as_policy(NeedsArguments)
