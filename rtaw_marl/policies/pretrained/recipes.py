"""The shipped policies' table: every name, and how each was trained, written once.

:data:`RECIPES` is the one source of the shipped names: the registry's
:data:`~rtaw_marl.policies.pretrained.registry.PRETRAINED` is its keys, and the zoo
(:mod:`rtaw_marl.training.zoo`) turns each entry into its exact ``rtaw-train`` command.
Each :class:`Recipe` names its scenario (a :data:`~rtaw_marl.scenarios.SCENARIOS`
name, with the simulator keys it changes), its network, its PPO budget and, for a staged
entry, the entry whose run it continues.

Five kinds of entries (:attr:`Recipe.stage`):

* ``train``: from scratch. The paper's network (``<scenario>``) and RTAW+
  (``<scenario>_plus``) get the same recipe and budget (docs/training.md): a warm start
  imitating ``lookahead`` (65,536 labelled decisions, DAgger), then :data:`BUDGET` PPO
  frames.
* ``continued``: Table I's policies at three times the budget (``<scenario>_long``,
  ``<scenario>_long_plus``): the base run continued from its ``last.pt`` to
  :data:`LONG_FRAMES` with the same recipe, in a copy of its folder.
* ``curriculum``: Table II's 500-robot RTAW+: the best checkpoint of the 100-robot
  RTAW+ run continued with 500 robots and 2,500-task episodes for
  :data:`CURRICULUM_FRAMES` more PPO frames (``frames=`` counts from that checkpoint),
  selected on seeds 1000-1004.
* ``generalist``: ``generalist_plus``, one RTAW+ for every setting: the actor of a
  specialist (:attr:`Recipe.base`) continued with a fresh critic on a scenario mix
  (:data:`~rtaw_marl.scenarios.mix.GENERALIST`) for :data:`GENERALIST_FRAMES` frames,
  selected on seeds 1000-1009 of a mix member.
* ``lorr``: learned schedulers for LoRR's problems with traffic (``lorr_random_plus``,
  ``lorr_warehouse_plus``): the actor of a shipped policy (:attr:`Recipe.base`)
  continued with a fresh critic on a LoRR problem (:attr:`Recipe.problem`, ``scenario=
  lorr``) with its own keys (:attr:`Recipe.keys`: the reward, ``candidates``, selection
  on tasks finished), selected on seeds 1000+ of the problem (docs/training.md,
  "Training with traffic on LoRR's problems").

Policies trained with 10 robots also run with 100 or 1000: the networks' sizes do not
depend on them. This module is plain Python (no torch, no Hydra).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

from rtaw_marl.scenarios import SCENARIOS, TABLE1_ROBOTS, Scenario, lorr_scenario
from rtaw_marl.scenarios.mix import GENERALIST

__all__ = [
    "BUDGET",
    "CURRICULUM_FRAMES",
    "GENERALIST_FRAMES",
    "GENERALIST_SECOND_STAGE",
    "LONG_FRAMES",
    "LORR_FRAMES",
    "LORR_KEYS",
    "RECIPES",
    "STAGES",
    "TABLE2_BASES",
    "Recipe",
]

#: PPO frames of a ``train`` entry, after its warm start.
BUDGET = 409_600
#: A ``continued`` entry's budget: three times :data:`BUDGET`.
LONG_FRAMES = 3 * BUDGET
#: PPO frames a ``curriculum`` entry adds to its base's best checkpoint.
CURRICULUM_FRAMES = 163_840
#: Table II's 100-robot scenarios: their policies and the bases of its curricula.
TABLE2_BASES = ("open300_direct_m100_random", "C256_astar_m100_random")
#: The generalist's PPO frames (150 batches of 8192: what fitted the session that
#: trained it, on 2 cores).
GENERALIST_FRAMES = 1_228_800
#: The generalist's second selection stage: four members of its mix (small and large
#: fleets, queues 5 and 10, both modes, four layouts), on seeds 1100-1139.
GENERALIST_SECOND_STAGE = (
    "A_astar_m100:m200:paper",
    "C_astar_m10:paper",
    "E_astar_m100:n5",
    "D_astar_m10:m50",
)
#: The kinds of entries.
STAGES = ("train", "continued", "curriculum", "generalist", "lorr")
#: The ``lorr`` entries' common keys: RTAW+ with a fleet summary for the critic, a third
#: of the zoo's learning rate (a continued actor), the 32 nearest queued tasks per
#: decision (LoRR's window holds 1.5 tasks per robot), selection on tasks finished every
#: 32,768 frames (the best three kept), one learner thread.
LORR_KEYS = (
    "model.fleet_summary=true",
    "algo.lr=0.0003",
    "candidates=32",
    "selection.metric=tasks_finished",
    "selection.every_frames=32768",
    "selection.keep=3",
    "torch_threads=1",
)
#: A ``lorr`` entry's PPO frames.
LORR_FRAMES = 393_216


@dataclass(frozen=True, kw_only=True)
class Recipe:
    """How one shipped policy is trained.

    Attributes:
        name: The shipped name (``rtaw_marl/policies/pretrained/<name>.pt``).
        scenario: Its :data:`~rtaw_marl.scenarios.SCENARIOS` name.
        sim: Simulator keys it changes on that scenario (a curriculum's 500 robots).
        model: ``rtaw`` (the paper's network) or ``rtaw_plus``.
        frames: PPO frames: the run's budget (``train``, ``continued``), or what it adds
            to its base's best checkpoint (``curriculum``).
        stage: ``train``, ``continued``, ``curriculum``, ``generalist`` or ``lorr`` (see
            the module docstring).
        base: The entry whose run it continues (staged entries).
        base_frames: A curriculum's base: its best checkpoint's PPO frames.
        seed: The training seed.
        mix: A generalist's training mix (:mod:`rtaw_marl.scenarios.mix`); its
            :attr:`scenario` (with :attr:`sim`) then only selects the checkpoints, and
            its actor starts from :attr:`base`'s (``init_actor``).
        second_stage: Settings (mix member names) of a second selection stage on fresh
            selection seeds (:mod:`rtaw_marl.training.selection`): the shipped
            checkpoint is the run's candidate that gains most there, not the first
            stage's best. Empty: ``best.pt``.
        problem: A ``lorr`` entry's LoRR problem file (``builtin:NAME`` or a path
            relative to the project's root); its :attr:`scenario` is then ``lorr``.
        keys: A ``lorr`` entry's further ``rtaw-train`` overrides, as spelled.
    """

    name: str
    scenario: str
    sim: Mapping[str, Any] = field(default_factory=dict)
    model: str = "rtaw"
    frames: int = BUDGET
    stage: str = "train"
    base: str | None = None
    base_frames: int = 0
    seed: int = 0
    mix: tuple[str, ...] = ()
    second_stage: tuple[str, ...] = ()
    problem: str | None = None
    keys: tuple[str, ...] = ()

    def setting(self) -> Scenario:
        """The scenario it trains on (with :attr:`sim`'s changes); a ``lorr`` entry's
        reads its problem file."""
        if self.problem is not None:
            sim = dict(self.sim)
            return lorr_scenario(self.problem, sim.pop("num_robots", None), **sim)
        return SCENARIOS[self.scenario].with_sim(**self.sim)

    @property
    def budget(self) -> int:
        """The run's ``frames=`` value (a curriculum counts from its base's best)."""
        return self.base_frames + self.frames if self.stage == "curriculum" else self.frames


def _recipes() -> list[Recipe]:
    table1 = [
        s
        for m in TABLE1_ROBOTS
        for s in (f"open60_direct_m{m}", *(f"{p}_astar_m{m}" for p in "ABCDE"))
    ]
    # The default warehouse's policies (the demo's): its commands spell the 10 robots.
    trained = [("shelves_astar_m10", "default", {"num_robots": 10})]
    trained += [(name, name, {}) for name in (*table1, *TABLE2_BASES)]
    out = [Recipe(name=n, scenario=s, sim=sim) for n, s, sim in trained]
    out += [
        Recipe(name=f"{n}_plus", scenario=s, sim=sim, model="rtaw_plus") for n, s, sim in trained
    ]
    for base, base_frames in zip(TABLE2_BASES, (368_640, 409_600), strict=True):
        out.append(
            Recipe(
                name=base.replace("_m100_", "_m500_") + "_plus", scenario=base,
                sim={"num_robots": 500, "num_tasks": 2500}, model="rtaw_plus",
                frames=CURRICULUM_FRAMES, stage="curriculum", base=f"{base}_plus",
                base_frames=base_frames,
            )
        )  # fmt: skip
    for name in table1:
        for plus, model in (("", "rtaw"), ("_plus", "rtaw_plus")):
            out.append(
                Recipe(
                    name=f"{name}_long{plus}", scenario=name, model=model, frames=LONG_FRAMES,
                    stage="continued", base=f"{name}{plus}",
                )
            )  # fmt: skip
    out.append(
        Recipe(
            name="generalist_plus", scenario="A_astar_m100",
            sim={"num_robots": 200, "episode_mode": "paper"}, model="rtaw_plus",
            frames=GENERALIST_FRAMES, stage="generalist", base="C_astar_m100_long_plus",
            mix=GENERALIST, second_stage=GENERALIST_SECOND_STAGE,
        )
    )  # fmt: skip
    return out + _lorr_recipes()


def _lorr_recipes() -> list[Recipe]:
    """The learned schedulers for LoRR's problems: the generalist's actor continued on the
    start kit's random map (100 robots, reward: travel to the pickup plus the task's
    length), then on the large warehouse with 2,000 robots (reward: the 2024 winner's
    pair cost)."""
    random_keys = ("sim.reward=ttd_length", "selection.seeds=[1000,1001,1002,1003,1004]",
                   "collector.envs_per_worker=16")  # fmt: skip
    warehouse_keys = ("sim.reward=pair_cost", "selection.seeds=[1000,1001]",
                      "collector.envs_per_worker=8")  # fmt: skip
    return [
        Recipe(
            name="lorr_random_plus", scenario="lorr", problem="builtin:random_32_32_20_100.json",
            sim={"horizon": 500}, model="rtaw_plus", frames=LORR_FRAMES, stage="lorr",
            base="generalist_plus", seed=7, keys=(*LORR_KEYS, *random_keys),
        ),
        Recipe(
            name="lorr_warehouse_plus", scenario="lorr",
            problem="../shared/maps/lorr/warehouse_large_5000.json",
            sim={"num_robots": 2000, "horizon": 500}, model="rtaw_plus", frames=LORR_FRAMES,
            stage="lorr", base="lorr_random_plus", seed=11, keys=(*LORR_KEYS, *warehouse_keys),
        ),
    ]  # fmt: skip


#: Every shipped policy's recipe, by name: ``train`` entries first, then the staged ones
#: (which continue them). Its keys are the shipped names.
RECIPES: Mapping[str, Recipe] = MappingProxyType({r.name: r for r in _recipes()})
