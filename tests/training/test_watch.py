"""Training you can watch: the rules as the bar, the warm start's progress and points on
the curve, the curve over frames and wall time, and the verdict against the best rule on
the evaluation seeds."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from rtaw_marl.config import compose, to_typed
from rtaw_marl.errors import ConfigError
from rtaw_marl.evaluation.best_rule import DEFAULT_RULES
from rtaw_marl.evaluation.evaluate import evaluate
from rtaw_marl.evaluation.stats import paired_difference
from rtaw_marl.policies import make_baseline
from rtaw_marl.policies.network import load_policy
from rtaw_marl.scenarios import EVAL_SEEDS
from rtaw_marl.sim.builder import build_sim
from rtaw_marl.training.evaluator import Evaluator
from rtaw_marl.training.imitation import IMITATION_FILE
from rtaw_marl.training.ppo import train
from rtaw_marl.training.verdict import Verdict
from rtaw_marl.viz.plots import curve_series, plot_training_curve

pytestmark = pytest.mark.integration

#: A run with a warm start: 3 rounds, 2 PPO evaluations.
WARM = [
    "scenario=poc", "frames=1024", "selection.every_frames=512", "collector.envs_per_worker=4",
    "imitation.teacher=lookahead", "imitation.frames=192", "imitation.rounds=3",
]  # fmt: skip


def _verdict(baseline: list[float], other: list[float]) -> Verdict:
    diff = paired_difference(baseline, other)
    return Verdict(Path("best.pt"), "hungarian", (1000, 1001, 1002), "ttd", (0, 1, 2, 3), diff)


def test_the_verdict_says_beats_loses_or_ties_by_the_interval() -> None:
    rule = [100.0, 110.0, 120.0, 130.0]
    better = _verdict(rule, [90.0, 101.0, 109.0, 118.0])
    assert better.outcome == "beats"
    assert better.line().startswith("verdict: best.pt beats hungarian (the best rule on ")
    assert "selection seeds 1000-1002) on evaluation seeds 0-3: TTD" in better.line()
    assert better.diff.pct_low is not None
    assert better.diff.pct_low > 0
    assert "TTD 104.5 against 115.0, a gain of +9.1% [+7.3, +10.9]" in better.line()
    assert _verdict(rule, [110.0, 121.0, 131.0, 142.0]).outcome == "loses to"
    tie = _verdict(rule, [99.0, 112.0, 119.0, 131.0])
    assert tie.outcome == "does not beat"
    assert "a tie within the noise" in tie.line()


def test_tasks_finished_verdicts_count_more_as_better() -> None:
    diff = paired_difference([100.0, 101.0, 99.0], [110.0, 111.0, 108.0], positive="higher")
    verdict = Verdict(Path("best.pt"), "pair_greedy", (1000,), "tasks_finished", (0, 1, 2), diff)
    assert verdict.outcome == "beats"
    assert "tasks finished 109.7 against 100.0" in verdict.line()


def test_the_evaluator_plays_every_rule_and_picks_the_best_as_the_bar(train_cfg) -> None:
    cfg = train_cfg(["scenario=poc"])
    seeds = [1000, 1001, 1002]
    evaluator = Evaluator(cfg.sim_spec(), seeds)
    assert list(evaluator.rules) == list(DEFAULT_RULES)
    sim = build_sim(cfg.sim_spec())
    played = evaluate(sim, {r: make_baseline(r) for r in DEFAULT_RULES}, seeds)
    for rule in DEFAULT_RULES:
        assert evaluator.rules[rule] == pytest.approx(played[rule]["ttd"])
    means = {rule: np.mean(played[rule]["ttd"]) for rule in DEFAULT_RULES}
    assert evaluator.rule == min(means, key=means.get)


def test_a_warm_started_run_shows_every_phase_and_ends_with_its_verdict(
    train_cfg, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    cfg = train_cfg([*WARM, "verdict=true", "progress=true", f"output_dir={tmp_path}"])
    result = train(cfg, tmp_path)
    err = capsys.readouterr().err
    for phase in ("rules:", "imitation:", "PPO:", "verdict:"):
        assert phase in err, f"no progress bar for {phase}"
    assert f"best_rule={result.rule} " in err

    rounds = json.loads((tmp_path / IMITATION_FILE).read_text())
    assert [row["round"] for row in rounds] == [0, 1, 2]
    assert all(row["ttd"] > 0 and row["wall_s"] > 0 for row in rounds)
    walls = [row["wall_s"] for row in rounds] + [row["wall_s"] for row in result.history]
    assert walls == sorted(walls), "the wall clock runs from the start, through both phases"
    assert (tmp_path / "training_curve.png").stat().st_size > 10_000

    # The verdict: best.pt and the best rule on the evaluation seeds, as rtaw-eval plays them.
    verdict = result.verdict
    assert verdict is not None
    assert verdict.rule == result.rule
    assert verdict.seeds == tuple(EVAL_SEEDS)
    sim = build_sim(cfg.sim_spec())
    played = evaluate(
        sim,
        {"rule": make_baseline(result.rule), "net": load_policy(result.best_checkpoint)},
        list(EVAL_SEEDS),
    )
    assert verdict.diff.baseline_mean == pytest.approx(np.mean(played["rule"]["ttd"]))
    assert verdict.diff.other_mean == pytest.approx(np.mean(played["net"]["ttd"]))
    stored = json.loads((tmp_path / "verdict.json").read_text())
    assert stored["line"] == verdict.line()
    assert stored["rule"] == result.rule


def test_a_best_teacher_imitates_the_rule_the_evaluator_chose(
    train_cfg, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    overrides = [o for o in WARM if not o.startswith("imitation.teacher")]
    cfg = train_cfg([*overrides, "imitation.teacher=best", "progress=true"])
    result = train(cfg, tmp_path)
    assert f"teacher={result.rule}" in capsys.readouterr().err


def test_the_curve_puts_the_warm_start_first_on_the_frames_axis() -> None:
    imitation = [
        {"round": 0, "decisions": 100, "ttd": 30.0, "wall_s": 1.0},
        {"round": 1, "decisions": 200, "ttd": 25.0, "wall_s": 2.0},
    ]
    history = [
        {"frames": 0, "ttd": 25.0, "wall_s": 3.0, "mpdm_ttd": 40.0},
        {"frames": 512, "ttd": 22.0, "wall_s": 5.0, "mpdm_ttd": 40.0},
    ]
    series = curve_series(history, imitation)
    assert series["frames"] == [100.0, 200.0, 200.0, 712.0]
    assert series["wall_s"] == [1.0, 2.0, 3.0, 5.0]
    assert series["value"] == [30.0, 25.0, 25.0, 22.0]
    assert series["imitation_points"] == [2.0]
    # Rows of runs before the warm start was evaluated have no TTD: left out.
    assert curve_series(history, [{"round": 0, "decisions": 100}])["frames"] == [0.0, 512.0]


def test_the_curve_draws_with_and_without_the_rules(tmp_path: Path) -> None:
    history = [{"frames": 0, "ttd": 25.0, "wall_s": 3.0, "mpdm_ttd": 40.0, "lookahead_ttd": 24.0}]
    rules = {"mpdm": [39.0, 41.0, 40.0], "hungarian": [23.0, 22.0, 24.0]}
    drawn = plot_training_curve(history, tmp_path / "a.png", rules=rules, rule="hungarian")
    assert drawn is not None
    assert drawn.stat().st_size > 10_000
    assert plot_training_curve(history, tmp_path / "b.png") is not None  # an older run's rows
    assert plot_training_curve([], tmp_path / "c.png") is None


def test_the_new_map_recipe_continues_the_generalist() -> None:
    cfg = to_typed(compose("train", ["recipe=new_map", "layout=open"]))
    assert cfg.init_actor == "generalist_plus"
    assert cfg.model.name == "rtaw_plus"
    assert cfg.model.fleet_summary
    assert (cfg.algo.lr, cfg.frames, cfg.selection.every_frames) == (0.0003, 409_600, 40_960)
    assert cfg.imitation.teacher == "best"
    assert cfg.selection.seeds == list(range(1000, 1040))
    assert cfg.verdict
    with pytest.raises(ConfigError, match="new_map"):
        compose("train", ["recipe=new_mpa"])
