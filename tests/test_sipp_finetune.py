"""experiments/sipp_finetune.py: its training command is a valid rtaw-train run on the
navigation table's setting."""

from __future__ import annotations

from experiment_scripts import load_experiment

from rtaw_marl.config import compose, to_typed

sf = load_experiment("sipp_finetune")


def test_command_continues_the_astar_policy_with_sipp_on_the_table_setting(monkeypatch):
    monkeypatch.setattr(sf, "load_checkpoint", lambda path: {"frames": 245_760, "path": path})
    cmd = sf.command("C", 81_920)
    assert cmd[0].endswith("rtaw-train")
    cfg = to_typed(compose("train", cmd[1:]))
    assert cfg.navigator.name == "sipp"
    assert (cfg.env.num_robots, cfg.env.num_tasks) == (10, 50)
    assert (cfg.env.noise_mean, cfg.env.noise_var) == (0.0, 0.0)
    assert cfg.frames == 245_760 + 81_920
    assert cfg.resume_new_scenario
    assert cfg.resume.endswith("runs/pretrained/C_astar_m10_plus/checkpoints/best.pt")
    assert min(cfg.eval.seeds) >= 1000  # selection never on the evaluation seeds
    assert cfg.output_dir.endswith("runs/sipp_finetune/C")
