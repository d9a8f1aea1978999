"""Learning proven against the baselines on the paper's small settings (slow tests)."""

from __future__ import annotations

import itertools
from pathlib import Path

import numpy as np
import pytest
import torch

from rtaw_marl.envs.torchrl import BatchedWarehouseEnv
from rtaw_marl.evaluation import evaluate
from rtaw_marl.evaluation.stats import paired_difference
from rtaw_marl.models.checkpoint import build_networks, load_checkpoint
from rtaw_marl.models.config import RTAWConfig
from rtaw_marl.policies import MPDM
from rtaw_marl.policies.network import load_policy
from rtaw_marl.sim.builder import SimSpec, build_sim
from rtaw_marl.training.ppo import train
from tests.training.conftest import POC_LAYOUT, POC_SIM

pytestmark = [pytest.mark.integration, pytest.mark.slow]


def _poc_optimum() -> float:
    """Exhaustive search over every action sequence of the proof of concept."""
    sim = build_sim(SimSpec.of(POC_SIM, POC_LAYOUT, "direct", "poc"))
    best = np.inf
    for actions in itertools.product(range(2), repeat=5):
        sim.reset(0)
        total = 0.0
        for a in actions:
            if sim.done or not sim.queue_mask[a]:
                break
            total -= sim.step(a)
        else:
            best = min(best, total)
    return float(best)


def test_poc_reaches_the_exhaustive_optimum(train_cfg, tmp_path: Path) -> None:
    """Paper appendix: optimum 17.94 (MPDM 22.74, RBTS 18.46); PPO finds it."""
    optimum = _poc_optimum()
    assert optimum == pytest.approx(17.936, abs=1e-3)
    cfg = train_cfg(["scenario=poc", "frames=6144", "selection.every_frames=1024", "seed=0"])
    result = train(cfg, tmp_path)
    assert result.history[0]["ttd"] > optimum + 0.5  # the untrained policy is not optimal
    assert result.best_ttd == pytest.approx(optimum, abs=1e-3)
    assert result.mpdm_ttd == pytest.approx(22.737, abs=1e-3)
    # The best checkpoint reproduces it through the evaluation path.
    sim = build_sim(SimSpec.of(POC_SIM, POC_LAYOUT, "direct", "poc"))
    policy = load_policy(result.best_checkpoint)
    sim.reset(0)
    total = 0.0
    while not sim.done:
        total -= sim.step(policy.act_sim(sim))
    assert total == pytest.approx(optimum, abs=1e-3)


def _prob_short_task(actor_state: dict, model_config: RTAWConfig | dict) -> float:
    """Mean probability the stochastic policy picks task A (slot 0) in two-task states."""
    actor, _ = build_networks(model_config)
    actor.load_state_dict(actor_state)
    env = BatchedWarehouseEnv(
        SimSpec.of(
            {"num_robots": 10, "num_tasks": 200, "queue_len": 2, "episode_mode": "paper"},
            {"name": "open", "width": 10, "height": 10},
            "direct",
            "two_task",
        ),
        num_envs=4,
        seed=123,
    )
    td = env.reset()
    probs = []
    with torch.no_grad():
        for _ in range(100):
            logits = actor(td["robots"], td["tasks"], td["agent"], td["action_mask"])
            probs.append(torch.softmax(logits, -1)[:, 0])
            td["action"] = torch.zeros(4, dtype=torch.long)
            td = env.step(td)["next"]
    return float(torch.cat(probs).mean())


def test_two_task_setting_beats_mpdm_by_45_percent(train_cfg, tmp_path: Path) -> None:
    """Paper: 49.9% below MPDM with 10 robots. Trained policy: >= 45%, and it learned it."""
    cfg = train_cfg(["scenario=two_task", "frames=20480", "selection.every_frames=10240", "seed=0"])
    untrained, _ = build_networks(cfg.model)
    before = _prob_short_task(untrained.state_dict(), cfg.model)
    result = train(cfg, tmp_path)
    improvement = 100 * (result.mpdm_ttd - result.best_ttd) / result.mpdm_ttd
    assert improvement >= 45.0
    # The policy at the end of training (best.pt is the first evaluation that reached
    # the best TTD: a tie keeps the earlier checkpoint).
    ckpt = load_checkpoint(result.last_checkpoint)
    after = _prob_short_task(ckpt["model"]["actor"], ckpt["model_config"])
    # Learning, not luck: the sampling policy went from a coin flip to the short task.
    assert before < 0.7
    assert after > 0.9


def test_rtaw_plus_warm_started_on_lookahead_beats_mpdm_on_held_out_seeds(
    train_cfg, tmp_path: Path
) -> None:
    """Default scenario, trained on 100-task episodes: imitating lookahead (two DAgger
    rounds), then a little PPO. The greedy RTAW+ policy beats MPDM on the evaluation
    seeds 0-19, paired, with a 95% interval above 0.

    It is evaluated on 300-task episodes of the same scenario: training seeds 0-3 give
    +6.6% to +7.8% with lower bounds +3.1% to +4.3% there, against lower bounds +0.7% to
    +5.4% on 100-task episodes. Another CPU's arithmetic trains other weights from the
    same seed; on 100-task episodes that once fell just below significance.
    """
    cfg = train_cfg([
        "model=rtaw_plus", "algo=ppo", "sim.num_tasks=100", "imitation.teacher=lookahead",
        "imitation.frames=8192", "imitation.rounds=2", "algo.frames_per_batch=2048",
        "algo.minibatch_size=512", "frames=2048", "selection.every_frames=2048", "seed=0",
    ])  # fmt: skip
    result = train(cfg, tmp_path)
    sim = build_sim(train_cfg(["model=rtaw_plus", "sim.num_tasks=300"]).sim_spec())
    policies = {"mpdm": MPDM(), "rtaw_plus": load_policy(result.best_checkpoint)}
    res = evaluate(sim, policies, list(range(20)))
    diff = paired_difference(res["mpdm"]["ttd"], res["rtaw_plus"]["ttd"])
    assert diff.pct > 0
    assert diff.significant
