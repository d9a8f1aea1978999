"""The zoo entries the training studies retrain (docs/training.md): each run's command is
its entry's recipe with what the study changes, and the runs compare on its scenario."""

from __future__ import annotations

from pathlib import Path

import pytest

from benchmarks import variants
from benchmarks.studies import STUDIES
from rtaw_marl.config import compose, to_typed
from rtaw_marl.errors import ConfigError
from rtaw_marl.policies.pretrained.registry import pretrained_path
from rtaw_marl.training.zoo import ZOO

pytestmark = pytest.mark.integration


def typed(cmd: list[str]):
    assert cmd[0].endswith("rtaw-train")
    return to_typed(compose("train", cmd[1:]))


def test_a_seed_of_an_ordinary_entry_is_its_recipe_with_the_seed(tmp_path: Path) -> None:
    cmd = variants.seed_command("C_astar_m10_plus", 1, tmp_path / "run", tmp_path)
    cfg, shipped = typed(cmd), to_typed(compose("train", ZOO["C_astar_m10_plus"].overrides()))
    assert cfg.seed == 1
    assert (cfg.output_dir, cfg.progress) == (str(tmp_path / "run"), False)
    for key in ("sim", "layout", "navigator", "tasks", "model", "algo", "imitation", "selection"):
        assert getattr(cfg, key) == getattr(shipped, key), key
    with pytest.raises(ConfigError, match="continues its base's own run"):
        variants.seed_command("C_astar_m10_long_plus", 1, tmp_path, tmp_path)


def test_a_curriculum_seed_continues_the_base_of_the_same_seed(monkeypatch, tmp_path) -> None:
    name = "open300_direct_m500_random_plus"
    with pytest.raises(ConfigError, match="train open300_direct_m100_random_plus with seed 2"):
        variants.seed_command(name, 2, tmp_path / "out", tmp_path)
    base = tmp_path / "open300_direct_m100_random_plus_s2" / "checkpoints" / "best.pt"
    base.parent.mkdir(parents=True)
    base.touch()
    monkeypatch.setattr(
        "rtaw_marl.models.checkpoint.load_checkpoint", lambda path: {"frames": 286_720}
    )
    cfg = typed(variants.seed_command(name, 2, tmp_path / "out", tmp_path))
    assert cfg.seed == 2
    assert cfg.resume == str(base)
    assert cfg.resume_new_scenario
    assert (cfg.sim.num_robots, cfg.layout.width, cfg.tasks.name) == (500, 300, "random")
    assert cfg.frames == 286_720 + 163_840  # the shipped curriculum's budget from its base
    assert min(cfg.selection.seeds) >= 1000  # selection never on the evaluation seeds
    shipped = to_typed(compose("train", ZOO[name].overrides()))
    assert (cfg.model, cfg.algo, cfg.sim, cfg.selection) == (
        shipped.model, shipped.algo, shipped.sim, shipped.selection,
    )  # fmt: skip


def test_the_ablated_command_is_the_entrys_plus_the_overrides(tmp_path: Path) -> None:
    (cmd,) = variants.ablation_commands(
        "C_astar_m10_plus", ["model.critic_fleet=false"], 1, tmp_path
    )
    cfg = typed(cmd)
    shipped = to_typed(compose("train", ZOO["C_astar_m10_plus"].overrides()))
    assert cfg.model.critic_fleet is False
    assert shipped.model.critic_fleet is True
    assert cfg.seed == 1
    assert (cfg.sim, cfg.algo, cfg.imitation) == (shipped.sim, shipped.algo, shipped.imitation)
    tag = variants.ablation_tag(["model.critic_fleet=false", "sim.queue_len=5"])
    assert tag == "critic-fleet-false_queue-len-5"
    assert variants.ablation_tag([], ["sim.queue_len=5"]) == "first-queue-len-5"


def test_a_first_stage_is_continued_on_the_entrys_own_scenario(tmp_path: Path) -> None:
    """The first stage runs the entry with those overrides for its frames; the run
    resumes its last checkpoint on the entry's own scenario, to the entry's budget."""
    run_dir = tmp_path / "C_astar_m10_plus_first-queue-len-5_s1"
    cmds = variants.ablation_commands(
        "C_astar_m10_plus", [], 1, run_dir, ["sim.queue_len=5"], 204_800
    )
    first, second = (typed(cmd) for cmd in cmds)
    assert (first.sim.queue_len, first.frames, first.seed) == (5, 204_800, 1)
    assert (second.sim.queue_len, second.frames, second.seed) == (10, 409_600, 1)
    assert second.resume == f"{first.output_dir}/checkpoints/last.pt"
    assert second.resume_new_scenario
    assert first.output_dir.endswith("C_astar_m10_plus_first-queue-len-5_s1_first")
    with pytest.raises(ConfigError, match="first stage"):
        variants.ablation_commands("C_astar_m10_plus", [], 1, run_dir, ["sim.queue_len=5"])


def test_sipp_finetune_continues_the_astar_policy_on_the_navigation_setting(tmp_path) -> None:
    runs = tmp_path / "runs"
    cfg = typed(variants.sipp_finetune_command("C", 81_920, tmp_path / "C", 245_760, runs))
    assert cfg.navigator.name == "sipp"
    assert (cfg.sim.num_robots, cfg.sim.num_tasks, cfg.sim.queue_len) == (10, 50, 10)
    assert (cfg.sim.noise_mean, cfg.sim.noise_var) == (0.0, 0.0)
    assert cfg.frames == 245_760 + 81_920
    assert cfg.resume_new_scenario
    assert cfg.resume == f"{runs}/C_astar_m10_plus/checkpoints/best.pt"
    assert min(cfg.selection.seeds) >= 1000  # selection never on the evaluation seeds
    assert cfg.output_dir == str(tmp_path / "C")
    assert cfg.model.name == "rtaw_plus"
    # The setting of the navigators study's SIPP rows, which the runs are evaluated on.
    cell = next(c for c in STUDIES["navigators"].cells([0]) if c.key == "C, sipp")
    assert cfg.sim_spec() == cell.scenario.spec() == variants.sipp_setting("C").spec()


@pytest.mark.parametrize("reward", variants.REWARDS)
def test_the_reward_ablation_trains_rtaw_on_layout_a(reward: str, tmp_path: Path) -> None:
    cfg = typed(variants.reward_command(reward, tmp_path / reward))
    assert cfg.sim.reward == reward
    assert (cfg.layout.preset, cfg.navigator.name, cfg.sim.num_robots) == ("A", "astar", 10)
    assert (cfg.frames, cfg.selection.every_frames, cfg.seed, cfg.model.name) == (
        102_400, 10_240, 0, "rtaw",
    )  # fmt: skip
    with pytest.raises(ConfigError, match="unknown reward"):
        variants.reward_command("speed", tmp_path)


def test_runs_are_evaluated_beside_the_rules_on_the_entrys_scenario(tmp_path: Path) -> None:
    ttd = variants.evaluate_runs(
        "C_astar_m10_plus", {"seed 0": pretrained_path("C_astar_m10_plus")}, [0], tmp_path
    )
    assert list(ttd) == [*variants.SPREAD_RULES, "seed 0"]
    assert all(len(v) == 1 for v in ttd.values())
    table = variants.runs_table(ttd)
    assert table.splitlines()[0] == "| run | mean TTD | vs mpdm | vs rbts | vs lookahead |"
    assert table.splitlines()[2].startswith("| seed 0 | ")
    assert "Rules' mean TTD: mpdm " in table
