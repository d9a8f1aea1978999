"""An executed episode in space and time: where every robot was at every second.

Collision-aware executors (``sipp``, ``cbs``: :mod:`rtaw_marl.sim.mapf.executors`)
produce a :class:`Schedule` when an episode ends. It is the common currency of the
conflict checker (:mod:`rtaw_marl.sim.mapf.conflicts`), which validates it on its own
code path, and of the GIF renderer (:mod:`rtaw_marl.viz.gif`).

Time is discrete (1 s per step). Cells are ``(x, y)`` with ``x`` the column and ``y``
the row of :attr:`rtaw_marl.sim.layout.Layout.obstacles`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["Schedule"]


@dataclass(frozen=True)
class Schedule:
    """Positions of all robots at integer times and the life of every served task.

    Attributes:
        positions: ``int64 [T + 1, M, 2]`` cell of robot ``m`` at time ``t`` for
            ``t = 0 .. T``; after its last move a robot stays where it is.
        tasks: ``int64 [K, 4]`` ``(ox, oy, dx, dy)`` of each task that was assigned.
        task_robot: ``int64 [K]`` robot that served each task.
        task_arrival: ``int64 [K]`` time the task entered the queue.
        task_assigned: ``int64 [K]`` decision time at which the robot got the task.
        task_pickup: ``int64 [K]`` time the robot reached the origin (the pickup).
        task_delivered: ``int64 [K]`` time the robot reached the destination.
        headings: ``int64 [T + 1, M]`` each robot's heading at each time (LoRR's 0 east,
            1 south, 2 west, 3 north) when robots turn (``navigator.turns``); ``None``
            when they move in any direction without turning.
        task_ids: ``int64 [K]`` each task's index in the episode's task stream (the
            simulator's records, :attr:`rtaw_marl.sim.core.WarehouseSim.tasks`; for a
            LoRR problem, LoRR's task id), the same task under the same id in every
            episode of one seed; ``None`` when unknown (a schedule built by hand).
    """

    positions: np.ndarray
    tasks: np.ndarray
    task_robot: np.ndarray
    task_arrival: np.ndarray
    task_assigned: np.ndarray
    task_pickup: np.ndarray
    task_delivered: np.ndarray
    headings: np.ndarray | None = None
    task_ids: np.ndarray | None = None

    @classmethod
    def of_tasks(
        cls, positions: np.ndarray, records: Any, served: np.ndarray,
        pickup: np.ndarray, delivered: np.ndarray, headings: np.ndarray | None = None,
    ) -> Schedule:  # fmt: skip
        """A schedule of the tasks ``served int [K]`` of an episode's records (an
        :class:`~rtaw_marl.sim.execution.EpisodeRecords`, which imports this module), with
        the executor's ``pickup`` and ``delivered`` times of every task (``int [T]``) and
        the robots' ``headings`` if they turn; ``served`` are the tasks' stream ids."""
        return cls(
            positions=positions,
            tasks=records.tasks[served].copy(),
            task_robot=records.task_robot[served].copy(),
            task_arrival=records.task_arrival[served].astype(np.int64),
            task_assigned=records.task_assigned[served].astype(np.int64),
            task_pickup=np.asarray(pickup)[served].astype(np.int64),
            task_delivered=np.asarray(delivered)[served].astype(np.int64),
            headings=headings,
            task_ids=np.asarray(served, dtype=np.int64).copy(),
        )

    @property
    def num_robots(self) -> int:
        """``M``."""
        return int(self.positions.shape[1])

    @property
    def horizon(self) -> int:
        """``T``, the last time step covered by :attr:`positions`."""
        return int(self.positions.shape[0]) - 1

    @property
    def task_ttd(self) -> np.ndarray:
        """``int64 [K]`` empty travel time per task: pickup minus assignment, waits included."""
        return self.task_pickup - self.task_assigned
