"""Training on a scenario mix (``mix=``): one run, batches from every member, and a
policy that then acts on each member and on a fleet size none of them had."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from rtaw_marl.evaluation.evaluate import evaluate
from rtaw_marl.models.checkpoint import load_checkpoint
from rtaw_marl.policies import MPDM
from rtaw_marl.policies.network import load_policy
from rtaw_marl.scenarios.mix import member_spec
from rtaw_marl.sim.builder import build_sim
from rtaw_marl.training.ppo import train

MIX = ["open60_direct_m10:t40", "A_astar_m10:m3:n4:t24:paper"]


def test_a_mix_trains_one_policy_for_every_member(train_cfg, tmp_path: Path) -> None:
    cfg = train_cfg(
        [
            "scenario=open60_direct_m10", "env.num_tasks=40", "model=rtaw_plus",
            "model.fleet_summary=true", f"mix=[{','.join(MIX)}]", "collector.envs_per_worker=4",
            "algo.frames_per_batch=256", "algo.minibatch_size=128", "frames=512",
            "eval.every_frames=256", "eval.seeds=[1000,1001]",
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
