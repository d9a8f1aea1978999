"""LoRR's reassignment in the simulator (``sim.reassign``), a part of
:class:`~rtaw_marl.sim.core.WarehouseSim`.

LoRR lets a scheduler change a robot's task until the robot reaches the task's first
errand. With ``sim.reassign`` an assigned task keeps its queue slot, *held* by its robot
(``queue_holder``), until the pickup; a free robot may take a held task
(:meth:`Reassignment.reassignable`), and the holder is then free at once where it
stands, deciding next in the same timestep; a scheduler may also free holders itself
(:meth:`Reassignment.release`, as a scheduler that re-pairs every robot each timestep
does). A task changes hands at most once per timestep (``task_moved``), so every
timestep's decisions end.
"""

from __future__ import annotations

import numpy as np

from rtaw_marl.errors import InvalidActionError
from rtaw_marl.sim.distances import TargetSlots
from rtaw_marl.sim.execution import Executor
from rtaw_marl.sim.queue_distances import QueueDistances

__all__ = ["Reassignment"]


class Reassignment:
    """The held tasks of a :class:`~rtaw_marl.sim.core.WarehouseSim` (its state lives
    there; the attributes below are the simulator's)."""

    queue_holder: np.ndarray
    queue_ids: np.ndarray
    queue_mask: np.ndarray
    task_moved: np.ndarray
    task_robot: np.ndarray
    task_assigned: np.ndarray
    task_ttd: np.ndarray
    task_finished: np.ndarray
    robot_xy: np.ndarray
    robot_free_at: np.ndarray
    time: float
    _reassign: bool
    _executor: Executor
    _slots: TargetSlots
    _queue_distances: QueueDistances
    _owed: np.ndarray

    def reassignable(self) -> np.ndarray:
        """``bool [N]``: the held slots a free robot may take now (``sim.reassign``): the
        task not picked up and not already moved in this timestep. All ``False``
        without reassignment."""
        held = self.queue_holder >= 0
        moved = self.task_moved[np.maximum(self.queue_ids, 0)] == self.time
        return held & ~moved

    def legal_actions(self) -> np.ndarray:
        """``bool [N]``: the slots the selected robot may take: :attr:`queue_mask`, and
        with ``sim.reassign`` the :meth:`reassignable` ones."""
        if not self._reassign:
            return self.queue_mask.copy()
        return self.queue_mask | self.reassignable()

    def robot_cells(self, robots: np.ndarray) -> np.ndarray:
        """``int64 [R, 2]`` where ``robots`` stand now: a free robot at its cell, a busy
        one (collision-aware lifelong executors) where it is on its way; with instant
        travel, where each is next free."""
        positions = getattr(self._executor, "positions", None)
        robots = np.asarray(robots, dtype=np.int64)
        return self.robot_xy[robots].copy() if positions is None else positions(robots)

    def distances_from(self, xy: np.ndarray, slots: np.ndarray) -> np.ndarray:
        """Distances ``float64 [R, K]`` from the cells ``xy int [R, 2]`` to the origins
        of ``slots int [K]`` (held slots included)."""
        return self._slots.distances_from(np.asarray(xy, dtype=np.int64), slots)

    def _hold(self, slot: int, robot: int) -> None:
        self.queue_mask[slot] = False
        self.queue_holder[slot] = robot
        self._queue_distances.slot_changed(slot)

    def release(self, robots: np.ndarray) -> None:
        """The ``robots int [R]`` give their held tasks back, as a scheduler that
        re-pairs every robot each timestep does in LoRR's simulator: each robot is free
        at once where it stands and decides in this timestep; its task is queued again
        (it has changed hands: no robot takes it from a holder again this timestep).

        Raises:
            InvalidActionError: A robot holds no task it may give back now (see
                :meth:`reassignable`), or a robot is named twice.
        """
        robots = np.asarray(robots, dtype=np.int64).reshape(-1)
        if len(np.unique(robots)) != len(robots):
            raise InvalidActionError(f"release: robots named twice in {robots.tolist()}")
        open_ = np.flatnonzero(self.reassignable())
        slot_of = dict(zip(self.queue_holder[open_].tolist(), open_.tolist(), strict=True))
        missing = [r for r in robots.tolist() if r not in slot_of]
        if missing:
            raise InvalidActionError(
                f"release: robots {missing} hold no task they may give back at "
                f"t={self.time:g} (not assigned, picked up, or moved this timestep)"
            )
        for robot in robots.tolist():
            slot = slot_of[robot]
            self._free_holder(slot)
            self._queue_distances.slot_changed(slot)

    def _take_held(self, slot: int) -> None:
        """The selected robot takes a held task: its holder is free now where it stands."""
        task = int(self.queue_ids[slot])
        if self.task_moved[task] == self.time:
            raise InvalidActionError(
                f"action {slot}: task {task} already changed hands at t={self.time:g}"
            )
        self._free_holder(slot)

    def _free_holder(self, slot: int) -> None:
        """Slot ``slot``'s holder is free now where it stands; its task is queued."""
        task, holder = int(self.queue_ids[slot]), int(self.queue_holder[slot])
        self.robot_xy[holder] = self._executor.release(holder, self.time)
        self.robot_free_at[holder] = self.time
        self._queue_distances.robot_moved(holder)
        self._owed[holder] = False  # its task is not finished: nothing new is revealed
        self.task_moved[task] = self.time
        # Unassigned again until a robot takes it: a task given back and left queued at
        # the horizon must not count as served, nor finished at its old estimate.
        self.task_robot[task] = -1
        self.task_assigned[task] = self.task_ttd[task] = self.task_finished[task] = np.nan
        self.queue_mask[slot] = True  # the common path assigns it (and holds it again)
        self.queue_holder[slot] = -1
