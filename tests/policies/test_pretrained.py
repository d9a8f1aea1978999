"""The shipped pretrained policies: present, loadable, self-describing, runnable anywhere."""

from __future__ import annotations

from pathlib import Path

import pytest

from rtaw_marl.errors import ConfigError
from rtaw_marl.evaluation import evaluate
from rtaw_marl.models.checkpoint import load_checkpoint
from rtaw_marl.policies.network import load_policy
from rtaw_marl.policies.pretrained import registry
from rtaw_marl.policies.pretrained.registry import PRETRAINED, pretrained_path
from rtaw_marl.sim.builder import SimSpec, build_sim
from rtaw_marl.training.config import upgrade_config

pytestmark = pytest.mark.unit


@pytest.mark.parametrize("name", sorted(PRETRAINED))
def test_pretrained_checkpoint_is_shipped_and_describes_itself(name: str) -> None:
    path = pretrained_path(name)
    assert path.stat().st_size < 200_000  # RTAW+ with its critic: about 135 KB
    ckpt = load_checkpoint(path)
    assert "optimizer" not in ckpt
    # The command that trained it (its recipe's: tests/training/test_zoo.py).
    assert ckpt["command"][0].endswith("rtaw-train")
    # The best checkpoint of the run, selected on seeds 1000+, never the evaluation seeds.
    assert 0 <= ckpt["frames"] <= ckpt["config"]["frames"]
    if ckpt["frames"] == 0:  # PPO never beat the warm start: the best is the warm start
        assert ckpt["config"]["imitation"]["teacher"] == "lookahead"
    # Stored as "eval" (the key's old name): read under today's name, "selection".
    assert min(upgrade_config(ckpt["config"])["selection"]["seeds"]) >= 1000
    assert ckpt["config"]["model"]["name"] == ("rtaw_plus" if name.endswith("_plus") else "rtaw")


@pytest.mark.parametrize("name", sorted(PRETRAINED))
def test_pretrained_policy_runs_on_other_sizes(name: str) -> None:
    """Trained with 10 robots and 10 slots; runs with 30 robots and 4 slots on another grid."""
    sim = build_sim(
        SimSpec.of(
            {"num_robots": 30, "num_tasks": 60, "queue_len": 4},
            {"name": "preset", "preset": "C", "width": 40, "height": 30},
            "astar",
            "random",
        )
    )
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
    sim = build_sim(SimSpec.of({"num_robots": 10, "num_tasks": 50}, layout, "astar", "designated"))
    res = evaluate(sim, {"old": policy}, [0, 1])
    assert res["old"]["tasks_served"] == [50, 50]


def test_unknown_pretrained_name_lists_available() -> None:
    with pytest.raises(ConfigError, match="available: A_astar_m10"):
        pretrained_path("nope")


def test_a_policy_missing_from_this_copy_names_the_command_that_retrains_it(
    monkeypatch, tmp_path: Path
) -> None:
    monkeypatch.setattr(registry, "SHIPPED", tmp_path)
    with pytest.raises(ConfigError, match=r"not shipped in this copy .*rtaw-zoo C_astar_m10$"):
        pretrained_path("C_astar_m10")
