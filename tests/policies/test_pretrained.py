"""The shipped pretrained policies: present, loadable, self-describing, runnable anywhere."""

from __future__ import annotations

from pathlib import Path

import pytest
import torch

from rtaw_marl.errors import ConfigError
from rtaw_marl.evaluation import evaluate
from rtaw_marl.models.checkpoint import load_checkpoint
from rtaw_marl.policies.network import load_policy
from rtaw_marl.policies.pretrained.registry import (
    CONTINUED,
    CURRICULUM,
    LONG_FRAMES,
    PRETRAINED,
    pretrained_path,
)
from rtaw_marl.sim.builder import SimSpec
from rtaw_marl.training.checkpoints import scenario_changes


@pytest.mark.parametrize("name", sorted(PRETRAINED))
def test_pretrained_checkpoint_is_shipped_and_describes_itself(name: str) -> None:
    path = pretrained_path(name)
    assert path.stat().st_size < 200_000  # RTAW+ with its critic: about 135 KB
    ckpt = load_checkpoint(path)
    assert "optimizer" not in ckpt
    # The recorded command is the registry's, so the policy can be retrained exactly.
    assert ckpt["command"][1 : 1 + len(PRETRAINED[name])] == PRETRAINED[name]
    # The best checkpoint of the run, selected on seeds 1000+, never the evaluation seeds.
    assert 0 <= ckpt["frames"] <= ckpt["config"]["frames"]
    if ckpt["frames"] == 0:  # PPO never beat the warm start: the best is the warm start
        assert ckpt["config"]["imitation"]["teacher"] == "lookahead"
    assert min(ckpt["config"]["eval"]["seeds"]) >= 1000
    assert ckpt["config"]["model"]["name"] == ("rtaw_plus" if name.endswith("_plus") else "rtaw")


@pytest.mark.parametrize("name", sorted(CURRICULUM))
def test_curriculum_policies_continue_their_base_with_500_robots(name: str) -> None:
    """Table II's RTAW+ continues the shipped 100-robot policy (its frame count) with 500
    robots, selected on seeds 1000+ of the 500-robot scenario."""
    base, base_frames = CURRICULUM[name]
    assert load_checkpoint(pretrained_path(base))["frames"] == base_frames
    ckpt = load_checkpoint(pretrained_path(name))
    assert ckpt["config"]["env"]["num_robots"] == 500
    assert ckpt["config"]["resume"] == f"runs/pretrained/{base}/checkpoints/best.pt"
    assert base_frames < ckpt["frames"] <= ckpt["config"]["frames"] == base_frames + 163_840


@pytest.mark.parametrize("name", sorted(CONTINUED))
def test_continued_policies_extend_their_base_run(name: str) -> None:
    """Table I's RTAW+ at three times the budget is the shipped base's own run, continued
    from its last checkpoint in a copy of its folder, same scenario and recipe."""
    base = load_checkpoint(pretrained_path(CONTINUED[name]))
    ckpt = load_checkpoint(pretrained_path(name))
    command = ckpt["command"]
    run_dir = next(c for c in command if c.startswith("output_dir=")).split("=", 1)[1]
    assert f"resume={run_dir}/checkpoints/last.pt" in command
    assert f"frames={LONG_FRAMES}" in command
    assert base["config"]["frames"] * 3 == LONG_FRAMES
    # The same run: its selection history starts with the base's, up to the base's best.
    assert ckpt["history"][: len(base["history"])] == base["history"]
    assert ckpt["history"][-1]["frames"] >= ckpt["frames"] >= base["frames"]
    if ckpt["frames"] == base["frames"]:  # no later evaluation beat the base's best
        assert ckpt["model"]["actor"].keys() == base["model"]["actor"].keys()
        assert all(
            torch.equal(v, base["model"]["actor"][k]) for k, v in ckpt["model"]["actor"].items()
        )
    else:  # a checkpoint of the continuation itself
        assert ckpt["config"]["frames"] == LONG_FRAMES
    assert scenario_changes(base["config"], ckpt["config"]) == []
    for key in ("model", "algo", "imitation", "seed"):
        assert ckpt["config"][key] == base["config"][key]


@pytest.mark.parametrize("name", sorted(PRETRAINED))
def test_pretrained_policy_runs_on_other_sizes(name: str) -> None:
    """Trained with 10 robots and 10 slots; runs with 30 robots and 4 slots on another grid."""
    sim = SimSpec.of(
        {"num_robots": 30, "num_tasks": 60, "queue_len": 4},
        {"name": "preset", "preset": "C", "width": 40, "height": 30},
        "astar",
        "random",
    ).build()
    res = evaluate(sim, {"rtaw": load_policy(pretrained_path(name))}, [0])
    assert res["rtaw"]["tasks_served"] == [60]


def test_first_release_rtaw_checkpoint_still_loads_and_evaluates() -> None:
    """A checkpoint written before RTAW+ existed (no model name, paper features only)
    still loads, reads the same observation entries and acts."""
    old = Path(__file__).resolve().parents[1] / "data" / "rtaw_v1_A_astar_m10.pt"
    ckpt = load_checkpoint(old)
    assert "name" not in ckpt["model_config"]
    policy = load_policy(old)
    assert policy.net.in_keys == ("robots", "tasks", "agent", "action_mask")
    layout = {"name": "preset", "preset": "A"}
    sim = SimSpec.of({"num_robots": 10, "num_tasks": 50}, layout, "astar", "designated").build()
    res = evaluate(sim, {"old": policy}, [0, 1])
    assert res["old"]["tasks_served"] == [50, 50]


def test_unknown_pretrained_name_lists_available() -> None:
    with pytest.raises(ConfigError, match="available: A_astar_m10"):
        pretrained_path("nope")
