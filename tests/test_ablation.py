"""experiments/ablation.py: an ablated run is the entry's own command plus the overrides."""

from __future__ import annotations

from experiment_scripts import load_experiment

from rtaw_marl.config import compose, to_typed
from rtaw_marl.policies.pretrained.registry import PRETRAINED

ab = load_experiment("ablation")


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
    assert ab.tag([], ["env.queue_len=5"]) == "first-queue-len-5"


def test_a_first_stage_is_continued_on_the_entrys_own_scenario(monkeypatch, tmp_path):
    """--first: the first stage runs the entry with those overrides for its frames; the
    run resumes its last checkpoint on the entry's own scenario, to the entry's budget."""
    commands = []
    monkeypatch.setattr(ab, "ROOT", tmp_path)
    monkeypatch.setattr(ab, "run", lambda cmd, log: commands.append(cmd))
    ab.train("C_astar_m10_plus", [], 1, ["env.queue_len=5"], 204_800)
    first, second = (to_typed(compose("train", cmd[1:])) for cmd in commands)
    assert (first.env.queue_len, first.frames, first.seed) == (5, 204_800, 1)
    assert (second.env.queue_len, second.frames, second.seed) == (10, 409_600, 1)
    assert second.resume == f"{first.output_dir}/checkpoints/last.pt"
    assert second.resume_new_scenario
    assert first.output_dir.endswith("C_astar_m10_plus_first-queue-len-5_s1_first")
