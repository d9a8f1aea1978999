"""A reservation table: which robot occupies which cell during which times.

The collision-aware fleets keep every robot's committed trajectory here, as
per-cell lists of occupied time intervals ``[start, end]`` (inclusive). A robot that
has finished its trajectory *holds* its last cell: its final interval ends at
:data:`INF` until it is given a new trajectory.

Committed trajectories are conflict-free, so the intervals of one cell never overlap
and each cell's list is sorted by start. The complement of a cell's intervals is its
list of *safe intervals*, the states of Safe Interval Path Planning.

Cells are those of :class:`~rtaw_marl.sim.mapf.grid.Grid` (flat indices).
"""

from __future__ import annotations

from bisect import bisect_left, bisect_right

__all__ = ["INF", "ReservationTable"]

#: "Forever": the end of a hold.
INF = 1 << 60


class ReservationTable:
    """Occupied intervals per cell, and each robot's own intervals in time order.

    Args:
        num_robots: Robots that can reserve cells.
    """

    def __init__(self, num_robots: int) -> None:
        # cell -> parallel sorted lists; absent cells are free at all times.
        self._starts: dict[int, list[int]] = {}
        self._ends: dict[int, list[int]] = {}
        self._robots: dict[int, list[int]] = {}
        self._safe: dict[int, list[tuple[int, int]]] = {}
        # robot -> its intervals as (cell, start), in time order.
        self._own: list[list[tuple[int, int]]] = [[] for _ in range(num_robots)]

    # ------------------------------------------------------------------ queries
    def occupant(self, cell: int, t: int) -> int:
        """The robot in ``cell`` at time ``t``, or ``-1``."""
        starts = self._starts.get(cell)
        if not starts:
            return -1
        i = bisect_right(starts, t) - 1
        if i >= 0 and self._ends[cell][i] >= t:
            return self._robots[cell][i]
        return -1

    def holder(self, cell: int) -> int:
        """The robot holding ``cell`` forever (its last interval ends at INF), or ``-1``."""
        ends = self._ends.get(cell)
        if ends and ends[-1] == INF:
            return self._robots[cell][-1]
        return -1

    def parked(self, t: int) -> list[int]:
        """Cells held forever by a robot that stands there since time ``t`` or earlier."""
        return [
            cell
            for cell, ends in self._ends.items()
            if ends and ends[-1] == INF and self._starts[cell][-1] <= t
        ]

    def safe_intervals(self, cell: int) -> list[tuple[int, int]]:
        """Maximal free intervals ``[(a, b), ...]`` of ``cell`` over ``[0, INF]``, sorted."""
        safe = self._safe.get(cell)
        if safe is None:
            safe = []
            t = 0
            for s, e in zip(self._starts.get(cell, ()), self._ends.get(cell, ()), strict=True):
                if s > t:
                    safe.append((t, s - 1))
                t = e + 1
            if t <= INF:
                safe.append((t, INF))
            self._safe[cell] = safe
        return safe

    # ------------------------------------------------------------------ updates
    def reserve(self, robot: int, t0: int, cells: list[int]) -> None:
        """Reserve ``cells[i]`` at time ``t0 + i`` for ``robot``; it holds the last cell after.

        The robot must hold nothing from ``t0`` on (see :meth:`release_from`).
        """
        start = t0
        for i in range(1, len(cells) + 1):
            if i == len(cells):
                self._insert(robot, cells[i - 1], start, INF)
            elif cells[i] != cells[i - 1]:
                self._insert(robot, cells[i - 1], start, t0 + i - 1)
                start = t0 + i

    def release_from(self, robot: int, t: int) -> None:
        """Drop every reservation of ``robot`` at times ``>= t``."""
        own = self._own[robot]
        while own:
            cell, start = own[-1]
            i = bisect_left(self._starts[cell], start)
            if start >= t:
                own.pop()
                del self._starts[cell][i], self._ends[cell][i], self._robots[cell][i]
                self._safe.pop(cell, None)
                continue
            if self._ends[cell][i] >= t:
                self._ends[cell][i] = t - 1
                self._safe.pop(cell, None)
            break

    def _insert(self, robot: int, cell: int, start: int, end: int) -> None:
        starts = self._starts.setdefault(cell, [])
        ends = self._ends.setdefault(cell, [])
        robots = self._robots.setdefault(cell, [])
        self._safe.pop(cell, None)
        own = self._own[robot]
        i = bisect_left(starts, start)
        if (
            own
            and own[-1][0] == cell
            and i > 0
            and robots[i - 1] == robot
            and ends[i - 1] == start - 1
        ):
            # The robot waits on: extend its previous interval in this cell.
            ends[i - 1] = end
            return
        starts.insert(i, start)
        ends.insert(i, end)
        robots.insert(i, robot)
        own.append((cell, start))
