"""The bar is the best rule of the setting, chosen on selection seeds (1000-1019), never
on the seeds a comparison reports."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from rtaw_marl.errors import ConfigError
from rtaw_marl.evaluation import SELECTION_SEEDS, choose_best_rule, compare, evaluate
from rtaw_marl.policies import make_baseline
from rtaw_marl.scenarios import SCENARIOS
from rtaw_marl.scenarios.lorr import lorr_scenario
from rtaw_marl.sim.builder import build_sim

pytestmark = pytest.mark.unit

SMALL = SCENARIOS["C_astar_m10"].with_sim(num_tasks=30)
RULES = ("mpdm", "rbts", "lookahead", "hungarian")


def test_the_best_rule_has_the_least_mean_ttd_on_the_selection_seeds() -> None:
    sim = build_sim(SMALL.spec())
    chosen = choose_best_rule(sim, RULES, seeds=[1000, 1001, 1002])
    direct = evaluate(sim, {r: make_baseline(r) for r in RULES}, [1000, 1001, 1002])
    means = {r: float(np.mean(direct[r]["ttd"])) for r in RULES}
    assert chosen.metric == "ttd"
    assert chosen.scores == pytest.approx(means)
    assert chosen.name == min(RULES, key=means.__getitem__)
    assert chosen.seeds == (1000, 1001, 1002)
    assert chosen.name in chosen.line()


def test_horizon_episodes_choose_by_tasks_finished(tmp_path: Path) -> None:
    from tests.sim.test_lorr import write_problem

    path = write_problem(tmp_path, "4\n1,7\n4,0\n3,5\n7,1\n")
    sim = build_sim(lorr_scenario(path, horizon=30).spec())
    chosen = choose_best_rule(sim, ("mpdm", "batch"), seeds=[1000, 1001])
    assert chosen.metric == "tasks_finished"
    assert chosen.name == max(("mpdm", "batch"), key=chosen.scores.__getitem__)


def test_evaluation_seeds_are_never_selection_seeds() -> None:
    sim = build_sim(SMALL.spec())
    with pytest.raises(ConfigError, match=r"never on evaluation seeds .*got 3"):
        choose_best_rule(sim, RULES, seeds=[1000, 3])


def test_compare_chooses_its_bar_on_the_selection_seeds() -> None:
    result = compare(make_baseline("mpdm"), SMALL, seeds=[0, 1], against=RULES, label="m")
    assert result.best_rule is not None
    assert result.best_rule.seeds == SELECTION_SEEDS
    assert result.best == min(RULES, key=result.best_rule.scores.__getitem__)
    with pytest.raises(ConfigError, match="seed 1000 is both a selection seed"):
        compare(make_baseline("mpdm"), SMALL, seeds=[0, 1000], against=RULES, label="m")


@pytest.mark.integration
def test_rtaw_eval_compare_to_best(cli) -> None:
    """The best rule is chosen first, evaluated even if not asked for, named in the
    report's first line and in results.json; seeds 1000-1019 are refused with it."""
    result = cli("eval", "scenario=poc", "policy=[mpdm]", "seeds=[0,1]", "compare_to=best",
                 "output=r.json", "progress=false")  # fmt: skip
    assert result.code == 0, result.err
    assert "best rule on selection seeds 1000-1019: lookahead" in result.out
    data = json.loads(Path("r.json").read_text())
    assert list(data["policies"]) == ["mpdm", "lookahead"]
    assert data["best_rule"]["name"] == "lookahead"
    assert data["best_rule"]["seeds"] == list(SELECTION_SEEDS)
    assert "lookahead" in data["comparisons"]["mpdm"]["vs"]
    refused = cli("eval", "scenario=poc", "policy=[mpdm]", "seeds=[0,1005]", "compare_to=best")
    assert refused.code == 2
    assert "compare_to=best chooses the best rule on seeds 1000-1019; seed 1005" in refused.err
