"""experiments/ablation.py: an ablated run is the entry's own command plus the overrides."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

from rtaw_marl.config import compose, to_typed
from rtaw_marl.policies.pretrained.registry import PRETRAINED

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "experiments"))  # the script imports seed_spread, beside it
_spec = importlib.util.spec_from_file_location("ablation", ROOT / "experiments" / "ablation.py")
ab = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(ab)


def test_the_ablated_command_is_the_entrys_plus_the_overrides(tmp_path):
    cmd = ab.command("C_astar_m10_plus", ["model.critic_fleet=false"], 1, tmp_path)
    assert cmd[1 : 1 + len(PRETRAINED["C_astar_m10_plus"])] == PRETRAINED["C_astar_m10_plus"]
    cfg = to_typed(compose("train", cmd[1:]))
    shipped = to_typed(compose("train", PRETRAINED["C_astar_m10_plus"]))
    assert cfg.model.critic_fleet is False
    assert shipped.model.critic_fleet is True
    assert cfg.seed == 1
    assert (cfg.env, cfg.algo, cfg.imitation) == (shipped.env, shipped.algo, shipped.imitation)
    assert (
        ab.tag(["model.critic_fleet=false", "env.queue_len=5"]) == "critic-fleet-false_queue-len-5"
    )
