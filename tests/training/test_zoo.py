"""The zoo's recipes: each shipped checkpoint records its recipe's command, the recipes
train on their named scenarios, ``+zoo=NAME`` is the recipe, and ``rtaw-zoo`` runs them."""

from __future__ import annotations

import dataclasses
import subprocess
import sys
from pathlib import Path

import pytest
import torch

from rtaw_marl.config import as_plain, compose, to_typed
from rtaw_marl.errors import ConfigError
from rtaw_marl.models.checkpoint import load_checkpoint
from rtaw_marl.policies.pretrained.recipes import RECIPES
from rtaw_marl.policies.pretrained.registry import PRETRAINED, SHIPPED, pretrained_path
from rtaw_marl.scenarios import SCENARIOS
from rtaw_marl.sim.maps import resolve_path
from rtaw_marl.training.checkpoints import scenario_changes
from rtaw_marl.training.config import upgrade_command, upgrade_config
from rtaw_marl.training.zoo import (
    BUDGET,
    CURRICULUM_FRAMES,
    LONG_FRAMES,
    STAGES,
    ZOO,
    Recipe,
    recipe,
    train_command,
)

pytestmark = pytest.mark.integration

STAGED = sorted(n for n, r in ZOO.items() if r.stage != "train")


def test_the_recipe_table_is_every_shipped_policy_and_names_real_scenarios() -> None:
    """One table: its names are the shipped ones (each a ``.pt`` beside it), the zoo's
    entries are its rows, and every row is a recipe that can run."""
    assert tuple(RECIPES) == PRETRAINED
    assert {p.stem for p in SHIPPED.glob("*.pt")} == set(RECIPES)
    assert list(ZOO) == list(RECIPES)
    for name, entry in RECIPES.items():
        assert ZOO[name] == Recipe.of(entry)
        assert entry.name == name
        assert entry.scenario in SCENARIOS or (entry.scenario, entry.stage) == ("lorr", "lorr")
        assert (entry.problem is not None) == (entry.stage == "lorr") == bool(entry.keys)
        assert entry.stage in STAGES
        assert entry.model == ("rtaw_plus" if name.endswith("_plus") else "rtaw")
        assert (entry.base is None) == (entry.stage == "train")
        if entry.base is not None:  # continues an entry listed before it
            assert list(RECIPES).index(entry.base) < list(RECIPES).index(name)
        if entry.stage == "generalist":  # continues a shipped specialist's actor
            assert RECIPES[entry.base].stage != "generalist"
            assert entry.mix
        elif entry.stage == "lorr":  # continues a shipped actor: the generalist's, or a
            assert RECIPES[entry.base].stage in ("generalist", "lorr")  # LoRR entry's
        else:
            assert entry.base is None or RECIPES[entry.base].stage == "train"
    with pytest.raises(ConfigError, match="available: A_astar_m10"):
        recipe("nope")


@pytest.mark.parametrize("name", sorted(ZOO))
def test_each_shipped_checkpoint_records_its_recipe(name: str) -> None:
    """The recorded command is the recipe's, so the policy can be retrained exactly
    (recorded with ``eval.*`` and ``env.*``, the old names of ``selection.*`` and
    ``sim.*``: the same keys)."""
    ckpt = load_checkpoint(pretrained_path(name))
    overrides = ZOO[name].overrides()
    command = upgrade_command(ckpt["command"])
    assert command[1 : 1 + len(overrides)] == overrides
    assert f"frames={ZOO[name].budget}" in command


def test_a_shipped_checkpoints_old_eval_section_reads_as_selection() -> None:
    """The shipped checkpoints record ``selection`` under its old name, ``eval`` (config
    and command): read under today's names, they are the recipe's own settings."""
    ckpt = load_checkpoint(pretrained_path("A_astar_m10"))
    assert "eval" in ckpt["config"]
    assert "selection" not in ckpt["config"]
    assert any(arg.startswith("eval.every_frames=") for arg in ckpt["command"])
    stored = upgrade_config(ckpt["config"])
    assert "eval" not in stored
    recipe_cfg = as_plain(to_typed(compose("train", ZOO["A_astar_m10"].overrides())))
    # (It predates selection.keep.)
    assert stored["selection"] == {k: recipe_cfg["selection"][k] for k in ("every_frames", "seeds")}
    # Its selection seeds compare under today's name (its sim section predates newer keys).
    changes = scenario_changes(ckpt["config"], recipe_cfg)
    assert not [c for c in changes if c.startswith(("selection", "eval"))], changes
    command = upgrade_command(ckpt["command"])
    assert not any(arg.startswith("eval.") for arg in command)
    assert to_typed(compose("train", command[1:])).selection.every_frames == 40_960
    assert upgrade_config(stored) == stored  # today's names pass through
    assert upgrade_command(command) == command


def test_a_shipped_checkpoints_old_env_section_reads_as_sim() -> None:
    """The shipped checkpoints record the simulator's keys under their old name, ``env``
    (config and command): read under today's names (``sim``, in the same place), they
    are the recipe's own keys, and the command composes as it is."""
    ckpt = load_checkpoint(pretrained_path("A_astar_m10"))
    assert "env" in ckpt["config"]
    assert "sim" not in ckpt["config"]
    assert any(arg.startswith("env.num_robots=") for arg in ckpt["command"])
    stored = upgrade_config(ckpt["config"])
    assert list(stored).index("sim") == list(ckpt["config"]).index("env")
    assert stored["sim"] == ckpt["config"]["env"]
    recipe_cfg = as_plain(to_typed(compose("train", ZOO["A_astar_m10"].overrides())))
    changes = scenario_changes(ckpt["config"], recipe_cfg)
    # The keys both name agree (it predates the newer simulator keys, which only one has).
    assert not [c for c in changes if c.startswith("sim.") and "None ->" not in c], changes
    assert not [c for c in changes if c.startswith("env.")], changes
    command = upgrade_command(ckpt["command"])
    assert not any(arg.startswith("env.") for arg in command)
    assert "sim.num_robots=10" in command
    assert to_typed(compose("train", command[1:])).sim.num_robots == 10


@pytest.mark.parametrize("name", sorted(ZOO))
def test_each_recipe_trains_on_its_scenario(name: str) -> None:
    """The command's spelling (the default tasks left out) composes the named scenario,
    as ``rtaw-train scenario=NAME`` and Python build it."""
    entry = ZOO[name]
    if entry.problem is not None:
        _lorr_recipe_trains_on_its_problem(entry)
        return
    spelled = to_typed(compose("train", entry.scenario_overrides())).sim_spec()
    assert spelled == entry.setting().spec()
    sim = [f"sim.{k}={v}" for k, v in entry.sim.items()]
    assert to_typed(compose("train", [f"scenario={entry.scenario}", *sim])).sim_spec() == spelled


def _lorr_recipe_trains_on_its_problem(entry: Recipe) -> None:
    """``scenario=lorr tasks.problem=P sim.*`` is :func:`lorr_scenario` of the problem
    (the paths as spelled and as resolved aside)."""
    problem = resolve_path(str(entry.problem))
    if not problem.is_file():
        pytest.skip(f"{entry.name}'s problem is not here: {problem}")
    spelled = to_typed(compose("train", entry.scenario_overrides())).sim_spec()
    built = entry.setting().spec()
    assert Path(built.tasks.problem).resolve() == problem.resolve()
    assert spelled.sim == built.sim
    assert spelled.navigator == built.navigator
    assert dataclasses.replace(spelled.tasks, problem=built.tasks.problem) == built.tasks
    assert dataclasses.replace(spelled.layout, problem=built.layout.problem) == built.layout


@pytest.mark.parametrize("name", [n for n in STAGED if ZOO[n].stage == "lorr"])
def test_lorr_policies_record_the_run_as_typed_and_its_recipe(name: str) -> None:
    """A LoRR entry's checkpoint records the recipe's command and config, and the run as
    typed (its base actor as a run's file, its problem as an absolute path): the same
    config but for those spellings. Selected on seeds 1000+ by tasks finished, on its
    problem's LoRR sizes."""
    entry = ZOO[name]
    ckpt = load_checkpoint(pretrained_path(name))
    typed = ckpt["trained_as"]["command"]
    for problem in (resolve_path(str(entry.problem)), Path(_arg(typed, "tasks.problem"))):
        if not resolve_path(str(problem)).is_file():  # the configs read the problem
            pytest.skip(f"{name}'s problem is not here: {problem}")
    assert typed[1] == "scenario=lorr"
    assert Path(_arg(typed, "tasks.problem")).name == Path(str(entry.problem)).name
    assert _arg(typed, "init_actor") in (entry.base, *_RUN_FILES[name])
    recipe_cfg = as_plain(to_typed(compose("train", ckpt["command"][1:])))
    stored = upgrade_config(ckpt["config"])
    # Keys added to rtaw-train since the checkpoint was trained, at their defaults.
    assert set(recipe_cfg) - set(stored) <= NEWER_KEYS
    assert stored == {k: v for k, v in recipe_cfg.items() if k in stored}
    spelled = {"init_actor", "output_dir", "progress", "layout", "tasks"}
    typed_cfg = as_plain(to_typed(compose("train", typed[1:])))
    assert {k: v for k, v in typed_cfg.items() if k not in spelled} == {
        k: v for k, v in recipe_cfg.items() if k not in spelled
    }
    assert min(stored["selection"]["seeds"]) >= 1000
    assert stored["selection"]["metric"] == "tasks_finished"
    assert "tasks_finished" in ckpt["eval"]
    assert ckpt["frames"] <= entry.budget == stored["frames"]


#: rtaw-train's keys newer than the shipped checkpoints (the end-of-run verdict: it does
#: not change what a run trains).
NEWER_KEYS = {"verdict"}

#: The run files a LoRR entry's base was trained as (the base's shipped best).
_RUN_FILES = {
    "lorr_random_plus": (),
    "lorr_warehouse_plus": ("runs/lorr_traffic_random/checkpoints/best.pt",),
}


def _arg(command: list[str], key: str) -> str:
    return next(a.split("=", 1)[1] for a in command if a.startswith(f"{key}="))


@pytest.mark.parametrize("name", [n for n in STAGED if ZOO[n].stage == "curriculum"])
def test_curriculum_policies_continue_their_base_with_500_robots(name: str) -> None:
    """Table II's RTAW+ continues the shipped 100-robot policy (its frame count) with 500
    robots, selected on seeds 1000+ of the 500-robot scenario."""
    entry = ZOO[name]
    assert load_checkpoint(pretrained_path(entry.base))["frames"] == entry.base_frames
    ckpt = load_checkpoint(pretrained_path(name))
    assert upgrade_config(ckpt["config"])["sim"]["num_robots"] == 500
    assert ckpt["config"]["resume"] == f"runs/pretrained/{entry.base}/checkpoints/best.pt"
    assert entry.base_frames < ckpt["frames"] <= ckpt["config"]["frames"] == entry.budget
    assert entry.budget == entry.base_frames + CURRICULUM_FRAMES
    assert min(upgrade_config(ckpt["config"])["selection"]["seeds"]) >= 1000


@pytest.mark.parametrize("name", [n for n in STAGED if ZOO[n].stage == "continued"])
def test_continued_policies_extend_their_base_run(name: str) -> None:
    """Table I's policies at three times the budget are the shipped base's own run,
    continued from its last checkpoint in a copy of its folder, same scenario and recipe."""
    base = load_checkpoint(pretrained_path(ZOO[name].base))
    ckpt = load_checkpoint(pretrained_path(name))
    command = ckpt["command"]
    run_dir = next(c for c in command if c.startswith("output_dir=")).split("=", 1)[1]
    assert f"resume={run_dir}/checkpoints/last.pt" in command
    assert f"frames={LONG_FRAMES}" in command
    assert base["config"]["frames"] == BUDGET
    assert LONG_FRAMES == 3 * BUDGET
    # The same run: its selection history starts with the base's, up to the base's best.
    assert ckpt["history"][: len(base["history"])] == base["history"]
    assert ckpt["history"][-1]["frames"] >= ckpt["frames"] >= base["frames"]
    if ckpt["frames"] == base["frames"]:  # no later evaluation beat the base's best
        actor = base["model"]["actor"]
        assert ckpt["model"]["actor"].keys() == actor.keys()
        assert all(torch.equal(v, actor[k]) for k, v in ckpt["model"]["actor"].items())
    else:  # a checkpoint of the continuation itself
        assert ckpt["config"]["frames"] == LONG_FRAMES
    assert scenario_changes(base["config"], ckpt["config"]) == []
    for key in ("model", "algo", "imitation", "seed"):
        assert ckpt["config"][key] == base["config"][key]


def test_every_zoo_option_is_its_recipe() -> None:
    """``+zoo=NAME`` composes exactly the recipe's overrides; continued entries are no
    zoo option (they resume a copy of their base's folder)."""
    for name, entry in ZOO.items():
        if entry.stage == "continued":
            with pytest.raises(ConfigError, match=name):
                compose("train", [f"+zoo={name}"])
            continue
        assert as_plain(to_typed(compose("train", [f"+zoo={name}"]))) == as_plain(
            to_typed(compose("train", entry.overrides()))
        ), name


def test_train_command_trains_into_the_run_folder(tmp_path: Path) -> None:
    cmd = train_command("A_astar_m10_long_plus", tmp_path / "x")
    assert cmd[0].endswith("rtaw-train")
    cfg = to_typed(compose("train", cmd[1:]))
    assert (cfg.output_dir, cfg.resume) == (
        str(tmp_path / "x"),
        f"{tmp_path / 'x'}/checkpoints/last.pt",
    )
    assert (cfg.frames, cfg.model.name, cfg.progress) == (LONG_FRAMES, "rtaw_plus", False)
    curriculum = train_command("C256_astar_m500_random_plus", tmp_path / "c", tmp_path / "runs")
    resume = f"resume={tmp_path / 'runs'}/C256_astar_m100_random_plus/checkpoints/best.pt"
    assert resume in curriculum


def test_the_zoo_module_imports_no_torch() -> None:
    code = "import sys, rtaw_marl.training.zoo; print('torch' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"
