"""Collision-aware executors: episodes executed by a fleet on the shared grid.

The policy still observes single-robot (A*) distances, as in the paper, which trains
with A* and tests with SIPP and CBS; the executor plans every assigned task with its
:class:`~rtaw_marl.sim.mapf.fleet.Fleet`: robots wait for each other, and a task's TTD
is the real arrival time at its origin minus the decision time, waits included. The
reward of a decision is the TTD as planned then (the single-robot estimate while the
robot has to wait to plan); once the episode is done the simulator's records hold the
executed times and :meth:`FleetExecutor.schedule` the executed episode.

Completion times come from the planned paths and are whole seconds, so the
simulator's completion noise must be zero (``sim.noise_mean=0 sim.noise_var=0``; the
``navigator=sipp``/``navigator=cbs`` config options set it).
"""

from __future__ import annotations

from abc import abstractmethod

import numpy as np

from rtaw_marl.errors import ConfigError, InvalidActionError, PlanningError
from rtaw_marl.sim.distances import DistanceModel
from rtaw_marl.sim.execution import EpisodeRecords, Executor, SimSettings, check_whole_seconds
from rtaw_marl.sim.layout import Layout
from rtaw_marl.sim.mapf.fleet import Fleet
from rtaw_marl.sim.mapf.grid import Grid
from rtaw_marl.sim.mapf.schedule import Schedule
from rtaw_marl.sim.mapf.strategies import CBSFleet, SIPPFleet

__all__ = ["CBSExecutor", "FleetExecutor", "SIPPExecutor"]


class FleetExecutor(Executor):
    """Collision-free execution by a :class:`Fleet`; subclasses choose the fleet.

    Args:
        time_limit: Seconds one planning call may take before
            :class:`~rtaw_marl.errors.PlanningTimeout` is raised.
    """

    def __init__(self, time_limit: float) -> None:
        if isinstance(time_limit, bool) or not (
            isinstance(time_limit, (int, float)) and time_limit > 0
        ):
            raise ConfigError(f"navigator.time_limit must be a positive number, got {time_limit!r}")
        self.time_limit = float(time_limit)
        self._fleet: Fleet | None = None
        self._done = False  # the current episode is finished: its schedule is complete

    @property
    def collision_aware(self) -> bool:
        return True

    @property
    def fleet(self) -> Fleet:
        """The fleet executing the episodes (after :meth:`bind`)."""
        if self._fleet is None:
            raise ConfigError(f"executor {self.name!r} is not bound to a simulator")
        return self._fleet

    def bind(self, config: SimSettings, layout: Layout, distance_model: DistanceModel) -> None:
        del distance_model  # planners use the grid; the policy keeps the model's distances
        if self._fleet is not None:
            raise ConfigError(
                f"executor {self.name!r} already belongs to a simulator; make one per simulator"
            )
        check_whole_seconds(config, self.name)
        self._fleet = self._make_fleet(Grid.from_layout(layout), config.num_robots)

    @abstractmethod
    def _make_fleet(self, grid: Grid, num_robots: int) -> Fleet:
        """The fleet of this strategy on ``grid``."""

    def reset(self, starts: np.ndarray, records: EpisodeRecords, rng: np.random.Generator) -> None:
        del rng  # no noise: times come from the planned paths
        _check_distinct(starts, self.name)
        self._records = records
        self._done = False
        self.fleet.reset(starts, records.robot_free_at, len(records.tasks))

    def assign(
        self,
        robot: int,
        now: float,
        task: int,
        row: np.ndarray,
        distance: float,
        length: float,
    ) -> tuple[float, float]:
        fleet, t = self.fleet, int(now)
        estimate = distance + length
        ox, oy, dx, dy = row.tolist()
        fleet.assign(robot, t, task, (ox, oy), (dx, dy))
        pickup, delivered = int(fleet.task_pickup[task]), int(fleet.task_delivered[task])
        self._records.robot_free_at[:] = fleet.estimated_free_at
        if pickup < 0:  # waiting to plan: single-robot distances
            return estimate - length, t + estimate
        return float(pickup - t), float(delivered if delivered >= 0 else pickup + length)

    def next_robot(self, now: float) -> tuple[int, float]:
        fleet = self.fleet
        free_at = fleet.free_at
        # Every robot waits for another: move some aside (or raise PlanningError). One
        # resolve may free a robot only partly (its path still ends in a wait), so repeat;
        # each round either frees a robot or raises, so M + 1 rounds are enough.
        for _ in range(fleet.num_robots + 1):
            if not np.isinf(free_at.min()):
                break
            fleet.resolve(int(now))
            self._records.robot_free_at[:] = fleet.estimated_free_at
        else:
            raise PlanningError(
                f"{self.name}: every robot is blocked at t={int(now)} and moving robots aside "
                "did not free any (a deadlock this planner cannot resolve)"
            )
        robot = int(free_at.argmin())
        return robot, float(free_at[robot])

    def finish(self, now: float) -> None:
        """Deliver every assigned task, then record the executed times."""
        fleet, rec = self.fleet, self._records
        fleet.finish(int(now))
        served = np.flatnonzero(rec.task_robot >= 0)
        rec.task_ttd[served] = fleet.task_pickup[served] - rec.task_assigned[served]
        rec.task_finished[served] = fleet.task_delivered[served]
        rec.robot_busy[:] = np.bincount(
            rec.task_robot[served],
            weights=rec.task_finished[served] - rec.task_assigned[served],
            minlength=fleet.num_robots,
        )
        rec.robot_free_at[:] = fleet.estimated_free_at
        self._done = True

    def schedule(self) -> Schedule:
        if not self._done:
            raise InvalidActionError("the schedule is complete only when the episode is done")
        fleet, rec = self.fleet, self._records
        served = np.flatnonzero(rec.task_robot >= 0)
        return Schedule.of_tasks(
            fleet.positions(), rec, served, fleet.task_pickup, fleet.task_delivered
        )

    def stats(self) -> dict[str, float]:
        """``planning_calls``, ``evacuations`` (robots moved out of another's way) and
        ``cbs_fallbacks`` of the episode."""
        return self.fleet.stats()


class SIPPExecutor(FleetExecutor):
    """Prioritized Safe Interval Path Planning (:class:`SIPPFleet`).

    Args:
        time_limit: Seconds one planning call may take.
    """

    name = "sipp"

    def _make_fleet(self, grid: Grid, num_robots: int) -> Fleet:
        return SIPPFleet(grid, num_robots, self.time_limit)


class CBSExecutor(FleetExecutor):
    """Conflict-Based Search over the moving robots (:class:`CBSFleet`).

    Args:
        time_limit: Seconds one planning call may take.
        max_nodes: High-level CBS nodes per call; past it the newly assigned robot plans
            alone around the others' paths (counted in ``cbs_fallbacks``).
    """

    name = "cbs"

    def __init__(self, time_limit: float, max_nodes: int) -> None:
        super().__init__(time_limit)
        if isinstance(max_nodes, bool) or not isinstance(max_nodes, int) or max_nodes < 1:
            raise ConfigError(f"navigator.max_nodes must be a positive integer, got {max_nodes!r}")
        self.max_nodes = max_nodes

    def _make_fleet(self, grid: Grid, num_robots: int) -> Fleet:
        return CBSFleet(grid, num_robots, self.time_limit, self.max_nodes)


def _check_distinct(starts: np.ndarray, name: str) -> None:
    """Robots that occupy cells cannot share one at the start.

    Raises:
        ConfigError: Two robots start on the same cell (named as ``(x, y)``).
    """
    cells = np.asarray(starts, dtype=np.int64).reshape(-1, 2)
    _, first, counts = np.unique(cells, axis=0, return_index=True, return_counts=True)
    if (counts > 1).any():
        a = int(first[np.flatnonzero(counts > 1)[0]])
        b = next(j for j in range(a + 1, len(cells)) if (cells[j] == cells[a]).all())
        x, y = (int(v) for v in cells[a])
        raise ConfigError(
            f"robots {a} and {b} both start at (x={x}, y={y}); navigator {name!r} keeps "
            "robots on distinct cells: give sim.robot_starts distinct cells"
        )
