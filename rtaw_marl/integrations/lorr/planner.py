"""The own executor as LoRR's planner: ``rtaw-lorr planner=pibt``.

The start kit's planner track (``python/user_planner``) imports a module named
``pyMAPFPlanner`` and calls ``pyMAPFPlanner(env)``, ``initialize(limit_ms)`` and, every
timestep, ``plan(limit_ms)``: one action per robot (LoRR's ``FW``, ``CR``, ``CCR``,
``W`` = 0, 1, 2, 3). Here :class:`FleetPlanner` answers with the own simulator's
lifelong PIBT under LoRR's action model (:mod:`~rtaw_marl.sim.mapf._turns`) and its
traffic-flow guidance (:mod:`~rtaw_marl.sim.mapf._guidance`), the very kernels
``navigator=pibt`` runs in ``rtaw-eval``: each timestep it reads the robots' cells,
headings and first goals from LoRR, plans one step for the whole fleet and returns the
actions. The kit's default scheduler assigns the tasks (LoRR's planner track).

Both simulators apply the same action model, so the cells and headings LoRR reports
are the ones the planner predicted; where they are not (``mismatches`` in the stats),
that robot's committed next cell is dropped and it is planned afresh.
"""

from __future__ import annotations

import json
import os
import time
import traceback
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from rtaw_marl.sim.config import SimConfig
from rtaw_marl.sim.distances import GridDistance
from rtaw_marl.sim.execution import EpisodeRecords
from rtaw_marl.sim.layout import Layout
from rtaw_marl.sim.mapf.pibt import _IDLE, _TO_PICKUP, PIBTExecutor
from rtaw_marl.utils.atomic import atomic_write

__all__ = ["PLANNER_SPEC_VARIABLE", "FleetPlanner", "PlannerSpec", "pyMAPFPlanner"]

#: The environment variable naming the planner's run spec.
PLANNER_SPEC_VARIABLE = "RTAW_LORR_PLANNER_SPEC"


@dataclass(frozen=True)
class PlannerSpec:
    """What one ``lifelong`` run of the planner track serves.

    Attributes:
        problem: The LoRR problem JSON (its map).
        stats: Where the planner writes its counts (JSON).
        timesteps: LoRR's ``simulationTime``: the stats are written at the last one.
        patience: ``navigator.patience``.
        guidance: ``navigator.guidance``.
        guide_replans: ``navigator.guide_replans``.
        seed: The planner's tie-breaking seed.
    """

    problem: str
    stats: str
    timesteps: int
    patience: int | None
    guidance: float
    guide_replans: int
    seed: int = 0

    def write(self, path: Path) -> None:
        atomic_write(path, lambda fh: fh.write(json.dumps(asdict(self), indent=1).encode()))

    @classmethod
    def read(cls, path: str | Path) -> PlannerSpec:
        return cls(**json.loads(Path(path).read_text(encoding="utf-8")))


class FleetPlanner(PIBTExecutor):
    """The PIBT executor driven from outside: LoRR's state in, one timestep's actions out.

    Args:
        layout: The problem's map.
        num_robots: LoRR's team size.
        patience: Timesteps before a robot not getting nearer its goal is stuck
            (``None``: no priority rotation).
        guidance: The guide paths' congestion weight (``0``: none).
        guide_replans: Guide paths re-planned per timestep besides the needed ones.
        seed: Seeds the tie-breaks and priority rotation.
    """

    def __init__(
        self,
        layout: Layout,
        num_robots: int,
        *,
        patience: int | None,
        guidance: float,
        guide_replans: int,
        seed: int = 0,
    ) -> None:
        super().__init__(
            stall_limit=1 << 30, patience=patience, record=False, turns=True,
            guidance=guidance, guide_replans=guide_replans,
        )  # fmt: skip
        settings = SimConfig(num_robots=num_robots, noise_mean=0.0, noise_var=0.0)
        self.bind(settings, layout, GridDistance(layout))
        self.width = layout.width
        self._started = False
        self._seed = seed
        self.mismatches = 0
        self.seconds = 0.0

    def plan(self, locations: np.ndarray, headings: np.ndarray, goals: np.ndarray) -> np.ndarray:
        """One timestep's actions, ``int64 [M]`` (0 forward, 1 clockwise, 2 counter-
        clockwise, 3 wait).

        Args:
            locations: ``int64 [M]`` each robot's cell, LoRR's ``row x width + column``.
            headings: ``int64 [M]`` LoRR's orientations (0 east, 1 south, 2 west, 3 north).
            goals: ``int64 [M]`` each robot's next errand's cell, ``-1`` for none.
        """
        start = time.perf_counter()
        locations = np.asarray(locations, dtype=np.int64)
        pos = self.index[locations // self.width, locations % self.width].astype(np.int64)
        if not self._started:
            self._begin(pos)
        off = (pos != self.pos) | (np.asarray(headings) != self.heading)
        if off.any():
            self.mismatches += int(off.sum())
            self.target[off] = -1
            self.pos[:] = pos
            self.heading[:] = headings
            self.occ_now[:] = -1
            self.occ_now[pos] = np.arange(len(pos))
        goals = np.asarray(goals, dtype=np.int64)
        goal = np.where(goals >= 0, self.index[goals // self.width, goals % self.width], -1)
        for robot in np.flatnonzero(goal != self.goal).tolist():
            self._set_goal(robot, int(goal[robot]))
        busy = goal >= 0
        self.phase[:] = np.where(busy, _TO_PICKUP, _IDLE)
        self._move(busy)
        self.t += 1
        self.since[busy] += 1
        self._progress(busy)
        self.max_stall = max(self.max_stall, int(self.since.max(initial=0)))
        if self.guidance > 0:
            self._guide_update()
        self.seconds += time.perf_counter() - start
        return self.action.copy()

    def _begin(self, pos: np.ndarray) -> None:
        """The episode's start: robots where LoRR put them, facing east (LoRR's start)."""
        m = len(pos)
        starts = self.cells[pos]
        empty = np.zeros(0)
        records = EpisodeRecords(
            tasks=np.zeros((0, 4), dtype=np.int64), task_arrival=empty, task_assigned=empty,
            task_ttd=empty, task_finished=empty, task_robot=np.zeros(0, dtype=np.int64),
            robot_busy=np.zeros(m), robot_free_at=np.zeros(m),
        )  # fmt: skip
        self.reset(starts, records, np.random.default_rng(self._seed))
        self._started = True

    def counts(self) -> dict[str, Any]:
        """The run's counts as a JSON object."""
        return {
            "timesteps": self.t,
            "seconds": round(self.seconds, 3),
            "mismatches": self.mismatches,
            **{k: v for k, v in self.stats().items() if k != "timesteps"},
        }


class pyMAPFPlanner:
    """LoRR's Python planner serving :class:`FleetPlanner` for the run spec.

    Args:
        env: LoRR's ``SharedEnvironment`` (its pybind11 binding, module ``MAPF``).
    """

    def __init__(self, env: Any) -> None:
        self.env = env
        self.spec = PlannerSpec.read(os.environ[PLANNER_SPEC_VARIABLE])
        self.planner: FleetPlanner | None = None
        self.errors: list[str] = []

    def initialize(self, preprocess_time_limit: int) -> bool:
        """Build the planner on the problem's map (and check it is LoRR's)."""
        del preprocess_time_limit
        from rtaw_marl.sim.lorr import read_problem

        try:
            layout = read_problem(self.spec.problem).layout()
            grid = np.asarray(list(self.env.map), dtype=bool).reshape(self.env.rows, self.env.cols)
            if grid.shape != layout.obstacles.shape or not np.array_equal(grid, layout.obstacles):
                raise ValueError(f"LoRR's map is not the map of {self.spec.problem}")

            def planner() -> FleetPlanner:
                return FleetPlanner(
                    layout, int(self.env.num_of_agents), patience=self.spec.patience,
                    guidance=self.spec.guidance, guide_replans=self.spec.guide_replans,
                    seed=self.spec.seed,
                )  # fmt: skip

            # One timestep planned and thrown away compiles the kernels here, in the
            # preprocessing time, not in LoRR's first timesteps (which would time out).
            # (On distinct free cells: LoRR has not placed its robots yet.)
            cells = np.flatnonzero(~layout.obstacles.ravel())[: int(self.env.num_of_agents)]
            planner().plan(cells, np.zeros_like(cells), cells)
            self.planner = planner()
        except BaseException:
            self._fail()
            raise
        return True

    def plan(self, time_limit: int) -> list[int]:
        """Every robot's action for this timestep."""
        del time_limit
        assert self.planner is not None, "initialize() was not called"
        env = self.env
        try:
            states = env.curr_states
            locations = np.fromiter((s.location for s in states), dtype=np.int64)
            headings = np.fromiter((s.orientation for s in states), dtype=np.int64)
            goals = np.fromiter(
                (g[0][0] if len(g) else -1 for g in env.goal_locations), dtype=np.int64
            )
            actions = self.planner.plan(locations, headings, goals)
        except BaseException:
            self._fail()
            raise
        if int(env.curr_timestep) + 1 >= self.spec.timesteps or env.curr_timestep % 100 == 0:
            self._write()
        return actions.tolist()

    def _fail(self) -> None:
        self.errors.append(traceback.format_exc(limit=4))
        self._write()

    def _write(self) -> None:
        counts = self.planner.counts() if self.planner is not None else {}
        text = json.dumps({**counts, "errors": self.errors})
        atomic_write(Path(self.spec.stats), lambda fh: fh.write(text.encode()))
