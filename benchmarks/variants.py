"""Zoo entries trained differently: another seed, extra overrides, a curriculum stage,
a fine-tuning on another navigator; and how those runs compare on the entry's scenario.

The studies of docs/training.md (``benchmarks/scripts/seed_spread.py``, ``ablation.py``,
``sipp_finetune.py``, ``reward_ablation.py``) are thin callers of this module: each run's
command is an entry's recipe (:mod:`rtaw_marl.training.zoo`) with what the study
changes, so the tests here compose every such command.
"""

from __future__ import annotations

import dataclasses
import re
import subprocess
from collections.abc import Mapping, Sequence
from pathlib import Path

from benchmarks.study import Cell, Study, Ttd, checkpoint, rule, run_study
from benchmarks.tables import mean_cell, vs
from rtaw_marl.errors import ConfigError, unknown_name
from rtaw_marl.evaluation.report import markdown_table
from rtaw_marl.scenarios import SCENARIOS, Scenario
from rtaw_marl.training.zoo import RUNS, recipe, rtaw_train

__all__ = [
    "REWARDS",
    "SPREAD_RULES",
    "ablation_commands",
    "ablation_tag",
    "evaluate_runs",
    "reward_command",
    "run_logged",
    "runs_table",
    "seed_command",
    "sipp_finetune_command",
    "sipp_setting",
]

#: The rules each run is compared with, by their label in the stored data.
SPREAD_RULES = ("mpdm", "rbts", "lookahead")


def run_logged(cmd: Sequence[str], log: Path) -> None:
    """Run ``cmd``, its output into ``log``.

    Raises:
        subprocess.CalledProcessError: The command failed.
    """
    log.parent.mkdir(parents=True, exist_ok=True)
    with log.open("w") as fh:
        subprocess.run(list(cmd), check=True, stdout=fh, stderr=subprocess.STDOUT)


def _command(overrides: Sequence[str], run_dir: Path) -> list[str]:
    return [rtaw_train(), *overrides, f"output_dir={run_dir}", "progress=false"]


def seed_command(name: str, seed: int, run_dir: Path, seeds_dir: Path) -> list[str]:
    """The command training entry ``name`` with ``seed`` into ``run_dir``: its recipe
    with ``seed=K``. A curriculum entry continues the best checkpoint of its base trained
    with the same seed (``<seeds_dir>/<base>_s<K>``), so each seed is a whole pipeline.

    Raises:
        ConfigError: Unknown name, a continued entry, or a curriculum's base run missing.
    """
    entry = dataclasses.replace(recipe(name), seed=seed)
    if entry.stage == "continued":
        raise ConfigError(f"{name} continues its base's own run: train the base with seeds")
    if entry.stage == "train":
        return _command(entry.overrides(), run_dir)
    base = seeds_dir / f"{entry.base}_s{seed}" / "checkpoints" / "best.pt"
    if not base.is_file():
        raise ConfigError(f"{base} is missing: train {entry.base} with seed {seed} first")
    from rtaw_marl.models.checkpoint import load_checkpoint  # torch: only when needed

    frames = int(load_checkpoint(base)["frames"])
    return _command(entry.continuing(str(base), frames), run_dir)


def ablation_tag(overrides: Sequence[str], first: Sequence[str] = ()) -> str:
    """A folder-safe name of the overrides: ``model.critic_fleet=false`` ->
    ``critic-fleet-false``; first-stage overrides get a ``first-`` prefix."""

    def name(o: str) -> str:
        return re.sub(r"[^A-Za-z0-9-]+", "-", o.rsplit(".", 1)[-1].replace("=", "-"))

    return "_".join([*(f"first-{name(o)}" for o in first), *map(name, overrides)])


def ablation_commands(
    name: str,
    overrides: Sequence[str],
    seed: int,
    run_dir: Path,
    first: Sequence[str] = (),
    first_frames: int = 0,
) -> list[list[str]]:
    """The commands of one ablated run, in order: entry ``name``'s recipe with ``seed``
    plus ``overrides``. With ``first``, a first stage trains the recipe plus ``first``
    for ``first_frames`` PPO frames (into ``<run_dir>_first``), and the run continues its
    last checkpoint on the entry's own scenario to the entry's budget (a curriculum).

    Raises:
        ConfigError: Unknown name, or ``first`` without frames.
    """
    entry = dataclasses.replace(recipe(name), seed=seed)
    if bool(first) != (first_frames > 0):
        raise ConfigError("a first stage needs both its overrides and its frames (> 0)")
    base = entry.overrides()
    if not first:
        return [_command([*base, *overrides], run_dir)]
    first_dir = run_dir.with_name(run_dir.name + "_first")
    resume = [f"resume={first_dir}/checkpoints/last.pt", "resume_new_scenario=true"]
    return [
        _command([*base, *first, f"frames={first_frames}"], first_dir),
        _command([*base, *overrides, *resume], run_dir),
    ]


def sipp_setting(layout: str) -> Scenario:
    """The navigation table's SIPP setting on preset ``layout``: 10 robots, 50
    designated tasks, no completion noise (the ``navigators`` study's)."""
    base = SCENARIOS[f"{layout}_astar_m10"]
    return dataclasses.replace(base, navigator="sipp").with_sim(
        num_tasks=50, noise_mean=0.0, noise_var=0.0
    )


def sipp_finetune_command(
    layout: str, frames: int, run_dir: Path, start_frames: int, runs: Path = RUNS
) -> list[str]:
    """The command continuing layout ``layout``'s A*-trained 10-robot RTAW+ (the best
    checkpoint of ``<runs>/<layout>_astar_m10_plus``, after ``start_frames`` PPO frames)
    with SIPP execution on :func:`sipp_setting` for ``frames`` more PPO frames, selected
    on seeds 1000-1009."""
    base = runs / f"{layout}_astar_m10_plus" / "checkpoints" / "best.pt"
    seeds = ",".join(str(s) for s in range(1000, 1010))
    return _command(
        [
            *sipp_setting(layout).overrides(), "model=rtaw_plus", "algo=ppo",
            f"frames={start_frames + frames}", "selection.every_frames=20480",
            f"selection.seeds=[{seeds}]", "seed=0", f"resume={base}", "resume_new_scenario=true",
        ],
        run_dir,
    )  # fmt: skip


#: The rewards of the paper's reward ablation (``sim.reward``).
REWARDS = ("ttd", "length", "ttd_length")


def reward_command(reward: str, run_dir: Path) -> list[str]:
    """The reward ablation's run: RTAW on layout A with A*, 10 robots, designated tasks,
    ``algo=ppo_fast``, 102,400 frames, seed 0, trained with ``sim.reward=<reward>``."""
    if reward not in REWARDS:
        raise unknown_name("reward", reward, list(REWARDS))
    setting = [o for o in SCENARIOS["A_astar_m10"].overrides() if o != "tasks=designated"]
    return _command(
        [*setting, "algo=ppo_fast", "frames=102400", "selection.every_frames=10240", "seed=0",
         f"sim.reward={reward}"],
        run_dir,
    )  # fmt: skip


def evaluate_runs(
    name: str,
    checkpoints: Mapping[str, Path],
    seeds: Sequence[int],
    output: Path,
    workers: int = 1,
) -> Ttd:
    """Per-seed TTDs of :data:`SPREAD_RULES` and of each checkpoint (by label) on entry
    ``name``'s own scenario (a study of one cell, journalled in ``output``)."""
    setting = recipe(name).setting()
    policies = {r: rule(r) for r in SPREAD_RULES}
    policies.update({label: checkpoint(path) for label, path in checkpoints.items()})
    cell = Cell(key=name, scenario=setting, policies=policies, seeds=tuple(seeds))
    study = Study(
        name=f"runs_{name}",
        description=f"training runs of {name}",
        cells=lambda _: [cell],
        render=lambda result, _: runs_table(result.ttd[name]),
        page=None,
        store=False,
    )
    return run_study(study, list(seeds), output, workers).ttd[name]


def runs_table(ttd: Ttd, rules: Sequence[str] = SPREAD_RULES) -> str:
    """Markdown: each run's mean TTD and paired difference against each rule, then the
    rules' means."""
    runs = [label for label in ttd if label not in rules]
    table = markdown_table(
        ["run", "mean TTD", *(f"vs {r}" for r in rules)],
        [
            [label, mean_cell(ttd, label), *(vs(ttd[r], ttd[label]) for r in rules)]
            for label in runs
        ],
    )
    means = ", ".join(f"{r} {mean_cell(ttd, r)}" for r in rules)
    return f"{table}\n\nRules' mean TTD: {means}."
