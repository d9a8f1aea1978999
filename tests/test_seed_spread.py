"""experiments/seed_spread.py: each training seed of a Table II row is a whole pipeline,
its 500-robot curriculum continuing the 100-robot base trained with the same seed."""

from __future__ import annotations

import pytest
from experiment_scripts import load_experiment

from rtaw_marl.config import compose, to_typed
from rtaw_marl.policies.pretrained.registry import PRETRAINED

ss = load_experiment("seed_spread")


def test_a_curriculum_seed_continues_the_base_of_the_same_seed(monkeypatch, tmp_path):
    base = tmp_path / "open300_direct_m100_random_plus_s2" / "checkpoints" / "best.pt"
    base.parent.mkdir(parents=True)
    base.touch()
    monkeypatch.setattr(ss, "SEEDS_DIR", tmp_path)
    monkeypatch.setattr(ss, "load_checkpoint", lambda path: {"frames": 286_720})
    cmd = ss.seed_command("open300_direct_m500_random_plus", 2, tmp_path / "out")
    assert cmd[0].endswith("rtaw-train")
    cfg = to_typed(compose("train", cmd[1:]))
    assert cfg.seed == 2
    assert cfg.resume == str(base)
    assert cfg.resume_new_scenario
    assert (cfg.env.num_robots, cfg.layout.width, cfg.tasks.name) == (500, 300, "random")
    assert cfg.frames == 286_720 + 163_840  # the shipped curriculum's budget from its base
    assert min(cfg.eval.seeds) >= 1000  # selection never on the evaluation seeds
    # Everything else is the shipped entry's recipe.
    shipped = to_typed(compose("train", PRETRAINED["open300_direct_m500_random_plus"]))
    assert (cfg.model, cfg.algo, cfg.env, cfg.eval) == (
        shipped.model,
        shipped.algo,
        shipped.env,
        shipped.eval,
    )


def test_a_curriculum_seed_without_its_base_says_which_command_trains_it(monkeypatch, tmp_path):
    monkeypatch.setattr(ss, "SEEDS_DIR", tmp_path)
    with pytest.raises(SystemExit, match=r"seed_spread\.py open300_direct_m100_random_plus"):
        ss.seed_command("open300_direct_m500_random_plus", 1, tmp_path / "out")


def test_an_ordinary_entry_is_the_registry_command_with_the_seed(tmp_path):
    cmd = ss.seed_command("C_astar_m10_plus", 1, tmp_path)
    assert cmd[1 : 1 + len(PRETRAINED["C_astar_m10_plus"])] == PRETRAINED["C_astar_m10_plus"]
    assert to_typed(compose("train", cmd[1:])).seed == 1
