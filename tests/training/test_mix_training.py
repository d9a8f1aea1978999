"""Training on a scenario mix (``mix=``): one run, batches from every member, and a
policy that then acts on each member and on a fleet size none of them had."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from rtaw_marl.errors import ConfigError
from rtaw_marl.evaluation.evaluate import evaluate
from rtaw_marl.models.checkpoint import load_checkpoint
from rtaw_marl.policies import MPDM
from rtaw_marl.policies.network import load_policy
from rtaw_marl.scenarios.mix import member_spec
from rtaw_marl.sim.builder import build_sim
from rtaw_marl.training.ppo import train

pytestmark = pytest.mark.integration

MIX = ["open60_direct_m10:t40", "A_astar_m10:m3:n4:t24:paper"]


def test_a_mix_trains_one_policy_for_every_member(train_cfg, tmp_path: Path) -> None:
    cfg = train_cfg(
        [
            "scenario=open60_direct_m10", "sim.num_tasks=40", "model=rtaw_plus",
            "model.fleet_summary=true", f"mix=[{','.join(MIX)}]", "collector.envs_per_worker=4",
            "algo.frames_per_batch=256", "algo.minibatch_size=128", "frames=512",
            "selection.every_frames=256", "selection.seeds=[1000,1001]",
            "imitation.teacher=lookahead", "imitation.frames=128", "imitation.rounds=2",
        ]
    )  # fmt: skip
    result = train(cfg, tmp_path)
    assert result.frames == 512
    ckpt = load_checkpoint(tmp_path / "checkpoints" / "last.pt")
    assert ckpt["config"]["mix"] == MIX
    assert ckpt["model_config"]["fleet_summary"] is True
    # Its critic reads the 8-wide fleet summary, whatever M.
    assert ckpt["model"]["critic"]["fleet_embed.0.weight"].shape[-1] == 8
    policy = load_policy(tmp_path / "checkpoints" / "last.pt")
    for member in (*MIX, "C_astar_m10:m37:t30"):
        spec = member_spec(member)
        ttd = evaluate(build_sim(spec), {"net": policy, "mpdm": MPDM()}, [0, 1])
        assert np.isfinite(ttd["net"]["ttd"]).all()
        assert len(ttd["net"]["ttd"]) == 2


def test_init_actor_starts_from_a_shipped_actor(train_cfg, tmp_path: Path) -> None:
    """The run's first evaluation (frame 0) plays the shipped actor: its greedy TTD on
    the selection seeds is the shipped policy's own."""
    cfg = train_cfg(
        [
            "scenario=C_astar_m10", "sim.num_tasks=40", "model=rtaw_plus",
            "model.fleet_summary=true", "init_actor=C_astar_m10_long_plus",
            "collector.envs_per_worker=4", "algo.frames_per_batch=256",
            "algo.minibatch_size=128", "frames=256", "selection.every_frames=256",
            "selection.seeds=[1000,1001]",
        ]
    )  # fmt: skip
    result = train(cfg, tmp_path)
    shipped = load_policy("C_astar_m10_long_plus")
    ttd = evaluate(build_sim(cfg.sim_spec()), {"shipped": shipped}, [1000, 1001])
    assert result.history[0]["frames"] == 0
    assert result.history[0]["ttd"] == pytest.approx(np.mean(ttd["shipped"]["ttd"]))


def test_init_actor_of_another_network_is_one_error(train_cfg, tmp_path: Path) -> None:
    cfg = train_cfg(["scenario=poc", "model=rtaw_plus", "init_actor=C_astar_m10",
                     "frames=512", "collector.envs_per_worker=4"])  # fmt: skip
    message = "init_actor=C_astar_m10: its actor has model.name='rtaw'"
    with pytest.raises(ConfigError, match=re.escape(message)):
        train(cfg, tmp_path)
