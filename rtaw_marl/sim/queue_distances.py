"""The fleet's distances to the queue, kept between decisions instead of recomputed.

Between two decisions of an episode one robot moves (the one just assigned: its free
cell becomes its task's destination) and one slot changes (refilled or emptied). The
``[M, N]`` distances from every robot's free cell to every queued origin and the
``[N, N]`` chain distances (each queued destination to each queued origin) therefore
change in one row and one column; recomputing them whole was most of an observation's
cost (90 us of the AEC env's 280 us step at ``M = 1000``). :class:`QueueDistances`
recomputes only the robots and slots the simulator reports changed
(:meth:`~rtaw_marl.sim.distances.TargetSlots.refresh`). Every entry is the distance
model's own value for its pair, so the kept matrices equal fresh ones bit for bit (the
tests compare them along episodes of every kind of queue targets).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from rtaw_marl.sim.distances import TargetSlots

__all__ = ["QueueDistances", "nearest_other_origin"]


@njit(cache=True, nogil=True)
def nearest_other_origin(chain: np.ndarray, mask: np.ndarray, out: np.ndarray) -> None:
    """``out[i]``: the least ``chain[i, j]`` over the queued slots ``j != i``, ``inf``
    when there is none or slot ``i`` is empty.

    Args:
        chain: ``float64 [N, N]`` from each slot's destination to each slot's origin.
        mask: ``bool [N]`` which slots hold a task.
        out: ``float64 [N]``, overwritten.
    """
    n = chain.shape[0]
    for i in range(n):
        best = np.inf
        if mask[i]:
            for j in range(n):
                if j != i and mask[j] and chain[i, j] < best:
                    best = chain[i, j]
        out[i] = best


class QueueDistances:
    """Cached fleet-to-queue and queue-chain distances of one simulator.

    The simulator reports what changes: :meth:`robot_moved` when a robot's free cell
    changes, :meth:`slot_changed` when a slot's task changes (its target in ``slots`` or
    its row), :meth:`clear` when its whole state is replaced (reset, loaded state).

    Args:
        slots: The simulator's queue targets (its distance model's ``target_slots``).
        num_robots: ``M``.
    """

    def __init__(self, slots: TargetSlots, num_robots: int) -> None:
        self._slots = slots
        n = slots.size
        self._fleet = np.zeros((num_robots, n), dtype=np.float64)
        self._chain = np.zeros((n, n), dtype=np.float64)
        self._nearest = np.zeros(n, dtype=np.float64)
        # The nearest other origin of single slots (nearest_of), kept per slot with the
        # slot that attains it, valid until that slot or the slot itself changes.
        self._near = np.full(n, np.inf)
        self._near_arg = np.full(n, -1, dtype=np.int64)
        self._near_ok = np.zeros(n, dtype=bool)
        self.clear()

    def clear(self) -> None:
        """Forget everything: the next queries recompute the whole matrices."""
        self._fleet_valid = self._chain_valid = False
        self._moved: list[int] = []
        self._changed: list[int] = []
        self._chain_changed: list[int] = []
        self._near_changed: list[int] = []
        self._near_ok[:] = False

    def robot_moved(self, robot: int) -> None:
        """Robot ``robot``'s free cell changed."""
        self._moved.append(robot)

    def slot_changed(self, slot: int) -> None:
        """Slot ``slot``'s origin target or destination row changed."""
        self.slots_changed([slot])

    def robots_moved(self, robots: np.ndarray | list[int]) -> None:
        """The free cells of ``robots`` changed (a loaded state's robots that moved)."""
        self._moved.extend(np.asarray(robots, dtype=np.int64).tolist())

    def slots_changed(self, slots: np.ndarray | list[int]) -> None:
        """The tasks of ``slots`` changed (a loaded state's queue)."""
        ids = np.asarray(slots, dtype=np.int64).tolist()
        self._changed.extend(ids)
        self._chain_changed.extend(ids)
        self._near_changed.extend(ids)

    def fleet(self, robot_xy: np.ndarray) -> np.ndarray:
        """Distances ``float64 [M, N]`` from each robot's cell ``robot_xy int [M, 2]`` to
        each slot's origin target: the cache itself, which the next query overwrites
        (copy before keeping or writing it)."""
        if not self._fleet_valid:
            self._fleet[:] = self._slots.distances_from(robot_xy)
            self._fleet_valid = True
        elif self._moved or self._changed:
            self._slots.refresh(robot_xy, self._fleet, _ids(self._moved), _ids(self._changed))
        self._moved.clear()
        self._changed.clear()
        return self._fleet

    def chain_nearest(self, queue_rows: np.ndarray, queue_mask: np.ndarray) -> np.ndarray:
        """``float64 [N]``: from each queued destination (``queue_rows int [N, 4]``) to the
        nearest origin of another queued task, ``inf`` when there is none or the slot is
        empty (:func:`nearest_other_origin`): the cache itself, as :meth:`fleet`'s."""
        ends = np.ascontiguousarray(queue_rows[:, 2:])
        if not self._chain_valid:
            self._chain[:] = self._slots.distances_from(ends)
            self._chain_valid = True
        elif self._chain_changed:
            changed = _ids(self._chain_changed)
            self._slots.refresh(ends, self._chain, changed, changed)
        self._chain_changed.clear()
        nearest_other_origin(self._chain, queue_mask, self._nearest)
        return self._nearest

    def nearest_of(
        self, slots: np.ndarray, queue_rows: np.ndarray, queue_mask: np.ndarray
    ) -> np.ndarray:
        """``float64 [K]``: :meth:`chain_nearest` of the slots ``slots int [K]`` only,
        without the ``[N, N]`` chain: each slot's value is kept with the slot attaining
        it and recomputed (its destination against every origin) only when the slot
        or that one changed; slots queued since are checked against the kept values
        (their origins against the kept destinations). Equal to a fresh computation
        (the tests compare them along episodes)."""
        self._near_update(queue_rows, queue_mask)
        slots = np.asarray(slots, dtype=np.int64)
        need = np.unique(slots[~self._near_ok[slots] & queue_mask[slots]])
        if len(need):
            chain = self._slots.distances_from(queue_rows[need, 2:])  # [R, N]
            other = np.broadcast_to(queue_mask, chain.shape).copy()
            other[np.arange(len(need)), need] = False
            chain = np.where(other, chain, np.inf)
            arg = chain.argmin(axis=1)
            self._near[need] = chain[np.arange(len(need)), arg]
            self._near_arg[need] = np.where(np.isfinite(self._near[need]), arg, -1)
            self._near_ok[need] = True
        return np.where(queue_mask[slots], self._near[slots], np.inf)

    def _near_update(self, queue_rows: np.ndarray, queue_mask: np.ndarray) -> None:
        """Apply the slot changes since the last :meth:`nearest_of` to the kept values."""
        if not self._near_changed:
            return
        changed = _ids(self._near_changed)
        self._near_changed.clear()
        self._near_ok[changed] = False
        self._near_ok &= ~np.isin(self._near_arg, changed)  # their nearest origin left
        added = np.unique(changed[queue_mask[changed]])
        live = np.flatnonzero(self._near_ok & queue_mask)
        if len(added) and len(live):
            d = self._slots.distances_from(queue_rows[live, 2:], added)  # [L, A]
            best = d.argmin(axis=1)
            value = d[np.arange(len(live)), best]
            closer = value < self._near[live]
            self._near[live[closer]] = value[closer]
            self._near_arg[live[closer]] = added[best[closer]]


def _ids(values: list[int]) -> np.ndarray:
    """``int64 [K]`` (repeats do no harm: the same values are written twice)."""
    return np.array(values, dtype=np.int64)
