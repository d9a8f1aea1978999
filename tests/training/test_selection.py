"""Selection without a winner's curse: ``selection.keep`` keeps the best evaluations'
checkpoints, and a second stage scores them on fresh selection seeds."""

from __future__ import annotations

from pathlib import Path

import pytest

import rtaw_marl.training.evaluator as evaluator_module
from rtaw_marl.errors import ConfigError
from rtaw_marl.evaluation.evaluate import evaluate
from rtaw_marl.evaluation.stats import pooled_difference
from rtaw_marl.models.checkpoint import load_checkpoint
from rtaw_marl.policies import make_baseline
from rtaw_marl.policies.network import load_policy
from rtaw_marl.policies.pretrained.registry import pretrained_path
from rtaw_marl.scenarios.mix import member_spec
from rtaw_marl.sim.builder import build_sim
from rtaw_marl.training.ppo import train
from rtaw_marl.training.selection import run_candidates, second_stage

pytestmark = pytest.mark.integration

TINY = [
    "scenario=poc", "selection.every_frames=512", "collector.envs_per_worker=4", "algo=ppo_paper",
]  # fmt: skip


def test_keep_holds_the_k_best_evaluations_and_drops_the_others(
    train_cfg, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Scripted selection TTDs at 0, 512, ..., 2048 frames: the two best (1536, then
    512) are the files in top/, each holding its evaluation's weights and row."""
    scripted = iter([5.0, 3.0, 4.0, 1.0, 6.0])
    monkeypatch.setattr(evaluator_module, "greedy_ttd", lambda net, env, seeds: [next(scripted)])
    run = tmp_path / "run"
    train(train_cfg([*TINY, "frames=2048", "selection.keep=2"]), run)
    top = sorted((run / "checkpoints" / "top").iterdir())
    assert [p.name for p in top] == ["000000000512.pt", "000000001536.pt"]
    for path, ttd in zip(top, (3.0, 1.0), strict=True):
        ckpt = load_checkpoint(path)
        assert ckpt["eval"]["ttd"] == ttd
        assert ckpt["frames"] == int(path.stem)
        assert "optimizer" not in ckpt
    assert list(run_candidates(run)) == ["frames_512", "frames_1536"]


def test_without_keep_the_candidates_are_best_and_last(
    train_cfg, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    scripted = iter([5.0, 3.0, 4.0])
    monkeypatch.setattr(evaluator_module, "greedy_ttd", lambda net, env, seeds: [next(scripted)])
    run = tmp_path / "run"
    train(train_cfg([*TINY, "frames=1024"]), run)
    assert not (run / "checkpoints" / "top").exists()
    assert list(run_candidates(run)) == ["frames_512", "frames_1024"]


SETTINGS = ("A_astar_m10:m5:t30", "C_astar_m10:m4:n5:t25:paper")
SEEDS = (1100, 1101, 1102, 1103)


def test_second_stage_picks_the_largest_pooled_gain_over_lookahead() -> None:
    candidates = {name: pretrained_path(name) for name in ("A_astar_m10", "A_astar_m10_plus")}
    result = second_stage(candidates, SETTINGS, SEEDS, first_stage=range(1000, 1010))
    pairs: dict[str, list] = {name: [] for name in candidates}
    for setting in SETTINGS:
        sim = build_sim(member_spec(setting))
        rules = {"lookahead": make_baseline("lookahead", env=sim)}
        nets = {name: load_policy(path, name=name) for name, path in candidates.items()}
        ttd = {k: r["ttd"] for k, r in evaluate(sim, {**rules, **nets}, list(SEEDS)).items()}
        assert ttd == result.ttd[setting]
        for name in candidates:
            pairs[name].append((ttd["lookahead"], ttd[name]))
    expected = {name: pooled_difference(p) for name, p in pairs.items()}
    assert {k: g.mean for k, g in result.gains.items()} == {k: g.mean for k, g in expected.items()}
    assert result.chosen == max(expected, key=lambda k: expected[k].mean)
    assert all(g.n == len(SETTINGS) * len(SEEDS) for g in result.gains.values())
    record = result.as_dict()
    assert record["chosen"] == result.chosen
    assert record["seeds"] == [1100, 1104]
    mean, low, high = record["gains_pct"][result.chosen]
    assert (mean, low, high) == (
        expected[result.chosen].mean,
        expected[result.chosen].low,
        expected[result.chosen].high,
    )
    assert low < mean < high


@pytest.mark.parametrize(
    ("seeds", "message"),
    [
        ((5, 1100), "second-stage seeds \\[5\\] are evaluation seeds"),
        ((1003, 1100), "second-stage seeds \\[1003\\] are the first stage's selection seeds"),
        ((1100, 1100), "second-stage seeds lists a seed more than once: 1100"),
    ],
)
def test_second_stage_seeds_must_be_fresh_selection_seeds(seeds: tuple, message: str) -> None:
    candidates = {"a": pretrained_path("A_astar_m10")}
    with pytest.raises(ConfigError, match=message):
        second_stage(candidates, SETTINGS, seeds, first_stage=range(1000, 1010))
