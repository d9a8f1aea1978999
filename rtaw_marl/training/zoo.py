"""The shipped policies' recipes as ``rtaw-train`` commands (the zoo).

The recipes themselves (each shipped name's scenario, network, budget and the run it
continues; the kinds of entries) are one table beside the shipped checkpoints,
:data:`rtaw_marl.policies.pretrained.recipes.RECIPES`. Here each becomes a zoo
:class:`Recipe`, which adds the command line: :meth:`Recipe.overrides` is the exact
``rtaw-train`` command line every shipped checkpoint records (``tests/training/
test_zoo.py`` checks each ``.pt`` against it), :func:`train_command` the whole command.
``rtaw-zoo`` (:mod:`rtaw_marl.cli.zoo`, run by :mod:`rtaw_marl.training.retrain`)
retrains entries into ``runs/pretrained/<name>`` and ships their best checkpoints.

This module is plain Python (no torch, no Hydra).
"""

from __future__ import annotations

import dataclasses
import sys
from collections.abc import Mapping
from pathlib import Path
from types import MappingProxyType

from rtaw_marl.errors import unknown_name
from rtaw_marl.policies.pretrained import recipes as shipped
from rtaw_marl.policies.pretrained.recipes import (
    BUDGET,
    CURRICULUM_FRAMES,
    LONG_FRAMES,
    RECIPES,
    STAGES,
)

__all__ = [
    "BUDGET",
    "CURRICULUM_FRAMES",
    "LONG_FRAMES",
    "RUNS",
    "STAGES",
    "ZOO",
    "Recipe",
    "recipe",
    "rtaw_train",
    "train_command",
]

#: Where ``rtaw-zoo`` trains (relative to the working directory): one folder per entry.
RUNS = Path("runs/pretrained")
#: Evaluations for checkpoint selection, every so many PPO frames.
EVERY_FRAMES = 40_960
#: The warm start of ``train`` entries (and of their continuations).
WARM_START = ("imitation.teacher=lookahead", "imitation.frames=65536")
#: A curriculum's selection seeds (fewer than the default ten: 500-robot episodes).
CURRICULUM_SEEDS = (1000, 1001, 1002, 1003, 1004)
#: Overrides the zoo's commands never spelled out: the default task stream.
UNSPELLED = frozenset({"tasks=designated"})
#: The generalist's keys besides its mix: a third of the zoo's learning rate (the actor
#: is continued, the critic starts fresh: at 1e-3 the first 160k frames made the actor
#: 4% worse on the selection seeds), a fleet summary for the critic (a mix's fleets
#: differ), two collector processes with two simulators of each of its 16 members, and two learner
#: threads (RTAW+'s update is twice as fast on both cores; the collectors wait for it).
GENERALIST_KEYS = (
    "algo.lr=0.0003",
    "model.fleet_summary=true",
    "collector.workers=2",
    "collector.envs_per_worker=32",
    "torch_threads=2",
)


class Recipe(shipped.Recipe):
    """A shipped policy's recipe (:class:`rtaw_marl.policies.pretrained.recipes.Recipe`)
    with its ``rtaw-train`` command line."""

    @classmethod
    def of(cls, entry: shipped.Recipe) -> Recipe:
        """The zoo's recipe of a table entry (the same fields)."""
        return cls(**{f.name: getattr(entry, f.name) for f in dataclasses.fields(entry)})

    def scenario_overrides(self) -> list[str]:
        """The scenario's ``rtaw-train`` overrides, as the zoo's commands spell them (a
        ``lorr`` entry's: ``scenario=lorr``, its problem and its :attr:`sim` keys)."""
        if self.problem is not None:
            sim = [f"sim.{k}={v}" for k, v in self.sim.items()]
            return [f"scenario={self.scenario}", f"tasks.problem={self.problem}", *sim]
        return [o for o in self.setting().overrides() if o not in UNSPELLED]

    def overrides(self, runs: Path = RUNS) -> list[str]:
        """The ``rtaw-train`` overrides of this entry (besides its run folder, and a
        continued entry's ``resume=``); a curriculum continues
        ``<runs>/<base>/checkpoints/best.pt``."""
        if self.stage == "curriculum":
            return self.continuing(f"{runs / str(self.base)}/checkpoints/best.pt", self.base_frames)
        if self.stage == "lorr":  # a shipped actor continued on a LoRR problem: own keys
            return [
                *self.scenario_overrides(), f"model={self.model}", "algo=ppo",
                f"frames={self.budget}", f"seed={self.seed}", f"init_actor={self.base}",
                *self.keys,
            ]  # fmt: skip
        if self.mix:  # a specialist's actor continued on the mix: no warm start
            start = (f"init_actor={self.base}", *GENERALIST_KEYS, f"mix=[{','.join(self.mix)}]")
            tail: tuple[str, ...] = start
            warm: tuple[str, ...] = ()
        else:
            tail, warm = (), WARM_START
        return [
            *self.scenario_overrides(), f"model={self.model}", "algo=ppo", *warm,
            f"frames={self.budget}", f"selection.every_frames={EVERY_FRAMES}", f"seed={self.seed}",
            *tail,
        ]  # fmt: skip

    def continuing(self, checkpoint: str, start_frames: int) -> list[str]:
        """A curriculum's overrides continuing ``checkpoint`` (a run of its base's
        scenario after ``start_frames`` PPO frames; another seed's, say) for
        :attr:`frames` more frames on this entry's scenario."""
        seeds = ",".join(map(str, CURRICULUM_SEEDS))
        return [
            *self.scenario_overrides(), f"model={self.model}", "algo=ppo",
            f"frames={start_frames + self.frames}", f"selection.every_frames={EVERY_FRAMES}",
            f"selection.seeds=[{seeds}]", f"seed={self.seed}",
            f"resume={checkpoint}", "resume_new_scenario=true",
        ]  # fmt: skip


#: Every shipped policy's recipe, by name, in the table's order: ``train`` entries
#: first, then the staged ones (which continue them).
ZOO: Mapping[str, Recipe] = MappingProxyType({n: Recipe.of(r) for n, r in RECIPES.items()})


def recipe(name: str) -> Recipe:
    """The recipe of shipped policy ``name``.

    Raises:
        ConfigError: Unknown name; the message lists the zoo.
    """
    try:
        return ZOO[name]
    except KeyError:
        raise unknown_name("zoo entry", name, list(ZOO)) from None


def rtaw_train() -> str:
    """The ``rtaw-train`` executable beside this Python interpreter."""
    return str(Path(sys.executable).with_name("rtaw-train"))


def train_command(name: str, run_dir: Path, runs: Path = RUNS) -> list[str]:
    """The command that trains entry ``name`` into ``run_dir``: what its checkpoint
    records (a continued entry resumes ``run_dir``, a copy of its base's run).

    Raises:
        ConfigError: Unknown name.
    """
    entry = recipe(name)
    resume = [f"resume={run_dir}/checkpoints/last.pt"] if entry.stage == "continued" else []
    return [
        rtaw_train(),
        *entry.overrides(runs),
        *resume,
        f"output_dir={run_dir}",
        "progress=false",
    ]
