"""The scenario registry: every named setting, written once.

A scenario is a warehouse a user can name on any command (``scenario=C_astar_m100``) or
in Python (``warehouse_v1.env(scenario=...)``), with the shipped policies trained on it.
Three families: the default warehouse and two small sanity settings (:func:`_basics`);
the 60x60 warehouses of the RTAW paper's layouts A-E and an open grid, with 10 and 100
robots (:func:`_warehouses_60x60`); and two large grids with random tasks, up to 1,000
robots (:func:`_large_grids`). The descriptions say which of the paper's tables each
reproduces; the tables themselves are the benchmarks project's (``benchmarks/``).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

from rtaw_marl.errors import lookup
from rtaw_marl.sim.builder import SimSpec

__all__ = ["EVAL_SEEDS", "ROWS", "SCENARIOS", "TABLE1_ROBOTS", "Scenario", "scenario"]

#: The evaluation seeds: never used for training or checkpoint selection (those use
#: seeds from 1000 on).
EVAL_SEEDS: tuple[int, ...] = tuple(range(20))

Spec = str | Mapping[str, Any]


@dataclass(frozen=True, kw_only=True)
class Scenario:
    """A named setting: a simulator spec and its evaluation settings.

    Attributes:
        name: The registry name (``scenario=NAME``).
        title: Its label in result tables (the key of its rows in benchmarks/data/*.json).
        description: One line, for listings and the generated YAML files.
        layout: A layout name or ``{"name": ..., **keys}`` mapping.
        navigator: A navigator name or mapping.
        tasks: A task-stream name or mapping.
        sim: Simulator keys that differ from :class:`~rtaw_marl.sim.config.SimConfig`'s
            defaults.
        policies: The shipped learned policies that belong to it, table label ->
            pretrained registry name (``RTAW+`` first).
        seeds: Its evaluation seeds.
    """

    name: str
    title: str
    description: str
    layout: Spec = "shelves"
    navigator: Spec = "astar"
    tasks: Spec = "designated"
    sim: Mapping[str, Any] = field(default_factory=dict)
    policies: Mapping[str, str] = field(default_factory=dict)
    seeds: tuple[int, ...] = EVAL_SEEDS

    def spec(self) -> SimSpec:
        """The typed simulator spec (what :func:`~rtaw_marl.sim.builder.build_sim` takes)."""
        return SimSpec.of(dict(self.sim), self.layout, self.navigator, self.tasks)

    def with_sim(self, **sim: Any) -> Scenario:
        """The same scenario with some simulator keys changed (``episode_mode="paper"``)."""
        return dataclasses.replace(self, sim={**self.sim, **sim})

    def choice(self, group: str) -> tuple[str, dict[str, Any]]:
        """The option name of ``group`` (``layout``, ``navigator``, ``tasks``) and the
        keys it sets besides."""
        spec = getattr(self, group)
        if isinstance(spec, str):
            return spec, {}
        keys = dict(spec)
        return str(keys.pop("name")), keys

    def overrides(self) -> list[str]:
        """The command-line overrides that select this scenario's groups and keys."""
        out = []
        for group in ("layout", "navigator", "tasks"):
            name, keys = self.choice(group)
            out.append(f"{group}={name}")
            out += [f"{group}.{k}={_value(v)}" for k, v in keys.items()]
        return out + [f"sim.{k}={_value(v)}" for k, v in self.sim.items()]


def _value(value: Any) -> str:
    if isinstance(value, bool):
        return str(value).lower()
    if isinstance(value, (list, tuple)):
        return "[" + ",".join(_value(v) for v in value) + "]"
    return str(value)


def _scenario(name: str, title: str, description: str, **fields: Any) -> Scenario:
    return Scenario(name=name, title=title, description=description, **fields)


#: The robot counts of the 60x60 warehouses (the paper's Table I): 10 and 100.
TABLE1_ROBOTS = (10, 100)


def _warehouses_60x60() -> list[Scenario]:
    """The 60x60 warehouses (500 designated tasks, queue of 10; the paper's Table I), as
    trained: each with its RTAW+ and the paper's network at 1,228,800 frames."""
    rows = [("open60_direct", "Direct (open 60x60)", "open", "direct", "the open 60x60 grid")]
    rows += [(f"{p}_astar", f"A* layout {p}", p, "astar", f"layout {p}") for p in "ABCDE"]
    out = []
    for stem, title, layout, navigator, where in rows:
        for m in TABLE1_ROBOTS:
            name = f"{stem}_m{m}"
            out.append(
                _scenario(
                    name,
                    f"{title}, M={m}",
                    f"Table I: {m} robots on {where}, {navigator}, 500 designated tasks",
                    layout=layout,
                    navigator=navigator,
                    sim={"num_robots": m},
                    policies={"RTAW+": f"{name}_long_plus", "RTAW": f"{name}_long"},
                )
            )
    return out


def _large_grids() -> list[Scenario]:
    """The large grids (random tasks over the whole grid, 5,000-task episodes in the
    paper's mode; its Table II) and the 100-robot settings their policies were trained
    on."""
    grids = [
        ("open300_direct", "Direct, open 300x300", {"name": "open", "width": 300, "height": 300},
         "direct"),
        ("C256_astar", "A*, layout C 256x256", {"name": "C", "width": 256, "height": 256},
         "astar"),
    ]  # fmt: skip
    out = []
    for stem, title, layout, navigator in grids:
        trained = f"{stem}_m100_random"
        out.append(
            _scenario(
                trained,
                f"M=100, {title}",
                f"Table II's training setting: 100 robots, {title}, random tasks",
                layout=layout,
                navigator=navigator,
                tasks="random",
                sim={"num_robots": 100},
                policies={"RTAW+": f"{trained}_plus", "RTAW": trained},
            )
        )
        for m in (500, 1000):
            out.append(
                _scenario(
                    f"{stem}_m{m}_random",
                    f"M={m}, {title}",
                    f"Table II: {m} robots, {title}, 5,000 random tasks, paper mode",
                    layout=layout,
                    navigator=navigator,
                    tasks="random",
                    sim={"num_robots": m, "num_tasks": 5000, "episode_mode": "paper"},
                    policies={"RTAW+": f"{stem}_m500_random_plus", "RTAW": trained},
                )
            )
    return out


def _basics() -> list[Scenario]:
    """The default warehouse and two small settings whose optimum is known (the paper's
    appendix)."""
    return [
        _scenario(
            "default",
            "shelves 60x60, A*, M=10",
            "The default warehouse: 60x60 shelves, A*, designated tasks, 10 robots",
            policies={"RTAW+": "shelves_astar_m10_plus", "RTAW": "shelves_astar_m10"},
        ),
        _scenario(
            "poc",
            "proof of concept",
            "The paper's proof of concept: 2 robots, 5 tasks, queue of 2, no noise "
            "(MPDM 22.737, RBTS 18.463, optimum 17.936)",
            layout={"name": "open", "width": 10, "height": 10},
            navigator="direct",
            tasks="poc",
            sim={
                "num_robots": 2,
                "num_tasks": 5,
                "queue_len": 2,
                "noise_mean": 0.0,
                "noise_var": 0.0,
                "robot_starts": [[2, 2], [6, 2]],
                "robot_free_times": [0.0, 2.0],
            },
        ),
        _scenario(
            "two_task",
            "two tasks",
            "The paper's two-task setting: (0,0)->(3,3) and (0,0)->(9,9) always queued, "
            "10 robots, 500 decisions on a 10x10 open grid (the paper reports MPDM 4183)",
            layout={"name": "open", "width": 10, "height": 10},
            navigator="direct",
            tasks="two_task",
            sim={"num_robots": 10, "num_tasks": 500, "queue_len": 2, "episode_mode": "paper"},
        ),
    ]


#: Every scenario by name.
SCENARIOS: Mapping[str, Scenario] = MappingProxyType(
    {s.name: s for s in (*_basics(), *_warehouses_60x60(), *_large_grids())}
)

#: The 60x60 warehouses as ``rtaw-eval row=NAME`` configs (a scenario with its shipped
#: policies; the paper's Table I rows): row name -> scenario name.
ROWS: Mapping[str, str] = MappingProxyType(
    {
        f"{row}{'' if m == 10 else f'_m{m}'}": f"{stem}_m{m}"
        for m in TABLE1_ROBOTS
        for row, stem in (("direct", "open60_direct"), *((p, f"{p}_astar") for p in "ABCDE"))
    }
)


def scenario(name: str) -> Scenario:
    """The scenario registered as ``name``.

    Raises:
        ConfigError: Unknown name; the message lists the registered ones.
    """
    return lookup(SCENARIOS, "scenario", name)
