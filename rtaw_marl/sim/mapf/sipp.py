"""Safe Interval Path Planning (Phillips and Likhachev, 2011) with ordered goals.

One robot plans around everyone else's reservations (:class:`ReservationTable`). A
search state is ``(cell, safe interval, goals visited)`` with the earliest arrival time
as its cost, so waiting is implicit: a robot may stay in a cell until its safe interval
ends. From a state the robot moves to a 4-connected neighbour at the earliest time the
neighbour's interval is entered, unless that move swaps cells with the robot arriving
where it stands (an edge conflict), in which case it leaves one step later.

Goals are visited in order; intermediate goals (a task's origin) count at the first
arrival, the final goal (its destination) only in a safe interval that never ends,
because the robot holds that cell afterwards. The heuristic, the true single-robot
distance to the next goal plus the distances between the remaining goals, is
admissible and consistent, so the first goal state popped has the earliest arrival.

The state space is finite (finitely many safe intervals), so a search without a
solution ends; a deadline bounds its time as well.
"""

from __future__ import annotations

import heapq
import time
from collections.abc import Sequence

import numpy as np

from rtaw_marl.errors import PlanningTimeout
from rtaw_marl.sim.mapf.grid import Grid
from rtaw_marl.sim.mapf.reservations import INF, ReservationTable

__all__ = ["sipp_plan"]

#: A search state: ``(cell, safe interval index, goals visited)``.
_State = tuple[int, int, int]


def sipp_plan(
    grid: Grid,
    table: ReservationTable,
    start: int,
    t0: int,
    goals: Sequence[int],
    deadline: float,
    blockers: set[int] | None = None,
) -> tuple[list[int], list[int]] | None:
    """Earliest-arrival path from ``start`` at ``t0`` through ``goals`` in order.

    Args:
        grid: The grid; its distance fields are the heuristic.
        table: Reservations of all other robots (the planning robot holds nothing from
            ``t0`` on).
        start: Start cell, occupied by the robot at ``t0``.
        t0: Start time.
        goals: Goal cells, at least one; the robot holds the last one afterwards.
        deadline: ``time.perf_counter()`` value after which the search gives up.
        blockers: When given and no path exists, receives the cells held forever by
            other robots next to the explored region: only releasing one of them can
            make a later search succeed (new reservations only shrink safe intervals).

    Returns:
        ``(cells, goal_times)``: the cell at each time ``t0, t0 + 1, ...`` up to the
        final arrival, and the arrival time at each goal; ``None`` when no path exists.

    Raises:
        PlanningTimeout: The search ran past ``deadline``.
    """
    fields = [grid.field(g) for g in goals]
    if not _goals_open(table, start, t0, goals, fields, blockers):
        return None
    if _walled_in(grid, table, start, t0, goals, blockers):
        return None
    search = _SafeIntervalSearch(grid, table, goals, fields)
    found = search.run(start, t0, deadline)
    if found is None and blockers is not None:
        blockers.update(search.held_around_explored())
    return found


def _goals_open(
    table: ReservationTable,
    start: int,
    t0: int,
    goals: Sequence[int],
    fields: Sequence[np.ndarray],
    blockers: set[int] | None,
) -> bool:
    """Cheap necessary conditions: every goal reachable and not held for good too early."""
    last = len(goals) - 1
    if any(int(f[start]) < 0 for f in fields):
        return False
    if table.holder(goals[last]) >= 0:
        if blockers is not None:
            blockers.add(goals[last])
        return False
    earliest = t0
    for k, goal in enumerate(goals[:last]):
        # A goal held forever from some time on must be reached before.
        earliest += int(fields[k][start if k == 0 else goals[k - 1]])
        safe = table.safe_intervals(goal)
        if table.holder(goal) >= 0 and (not safe or earliest > safe[-1][1]):
            if blockers is not None:
                blockers.add(goal)
            return False
    return True


def _walled_in(
    grid: Grid,
    table: ReservationTable,
    start: int,
    t0: int,
    goals: Sequence[int],
    blockers: set[int] | None,
) -> bool:
    """Whether robots parked since ``t0`` or earlier cut ``start`` off from a goal.

    Parked robots never move during this search, so they are walls: one flood fill
    answers what a full SIPP search would find out slowly.
    """
    parked = table.parked(t0)
    if not parked:
        return False
    reach = grid.reachable(start, walls=parked)
    if all(reach[g] for g in goals):
        return False
    if blockers is not None:
        blockers.update(c for c in parked if any(reach[n] for n in grid.neighbours(c)))
    return True


class _SafeIntervalSearch:
    """A* over ``(cell, safe interval, goals visited)`` states for one planning call."""

    def __init__(
        self,
        grid: Grid,
        table: ReservationTable,
        goals: Sequence[int],
        fields: Sequence[np.ndarray],
    ) -> None:
        self.grid = grid
        self.table = table
        self.goals = goals
        self.fields = fields
        self.last = len(goals) - 1
        # rest[k]: distance still to cover after reaching goal k.
        self.rest = [0] * len(goals)
        for k in range(self.last - 1, -1, -1):
            self.rest[k] = self.rest[k + 1] + int(fields[k + 1][goals[k]])
        self.best: dict[_State, int] = {}
        self.parent: dict[_State, _State | None] = {}
        self.heap: list[tuple[int, int, int, int, int]] = []

    def run(self, start: int, t0: int, deadline: float) -> tuple[list[int], list[int]] | None:
        """The search from ``start`` at ``t0``; ``None`` once every state is explored."""
        table, final, last = self.table, self.goals[self.last], self.last
        i0 = next((i for i, (a, b) in enumerate(table.safe_intervals(start)) if a <= t0 <= b), None)
        if i0 is None:
            raise AssertionError(f"start cell {start} is reserved at t={t0}")
        k0 = self._advance(start, 0)
        self.best[(start, i0, k0)] = t0
        self.parent[(start, i0, k0)] = None
        h0 = int(self.fields[k0][start]) + self.rest[k0]
        self.heap.append((t0 + h0, -t0, start, i0, k0))
        pops = 0
        while self.heap:
            _, neg_g, cell, i, k = heapq.heappop(self.heap)
            g = -neg_g
            if self.best[(cell, i, k)] < g:
                continue
            end = table.safe_intervals(cell)[i][1]
            if k == last and cell == final and end == INF:
                return self._reconstruct((cell, i, k), t0)
            pops += 1
            if (pops & 511) == 1 and time.perf_counter() > deadline:
                raise PlanningTimeout(f"SIPP ran past its time limit after {pops} expansions")
            self._expand(cell, i, k, g, end)
        return None

    def _advance(self, cell: int, k: int) -> int:
        """Goals visited once on ``cell`` after ``k`` of them (intermediate goals count now)."""
        goals, last = self.goals, self.last
        while k < last and goals[k] == cell:
            k += 1
        return k

    def _expand(self, cell: int, i: int, k: int, g: int, end: int) -> None:
        """Push the neighbour states of ``cell``, reached at ``g`` and safe until ``end``."""
        table, best, fields = self.table, self.best, self.fields
        field = fields[k]
        key = (cell, i, k)
        for nxt in self.grid.neighbours(cell):
            if int(field[nxt]) < 0:
                continue
            for j, (a, b) in enumerate(table.safe_intervals(nxt)):
                if a > end + 1:
                    break
                if b < g + 1:
                    continue
                arrive = max(g + 1, a)
                leave_by = min(b, end + 1)
                # Leaving one step later avoids a swap with a robot moving nxt -> cell.
                while arrive <= leave_by and _swaps(table, cell, nxt, arrive):
                    arrive += 1
                if arrive > leave_by:
                    continue
                k2 = self._advance(nxt, k)
                nkey = (nxt, j, k2)
                if arrive < best.get(nkey, INF):
                    best[nkey] = arrive
                    self.parent[nkey] = key
                    h = int(fields[k2][nxt]) + self.rest[k2]
                    heapq.heappush(self.heap, (arrive + h, -arrive, nxt, j, k2))

    def held_around_explored(self) -> set[int]:
        """Cells held forever by other robots next to the cells this search explored."""
        explored = {cell for cell, _, _ in self.best}
        return {
            nxt
            for cell in explored
            for nxt in self.grid.neighbours(cell)
            if self.table.holder(nxt) >= 0
        }

    def _reconstruct(self, key: _State, t0: int) -> tuple[list[int], list[int]]:
        """The cell at every time from ``t0`` and the goal times, from parent links."""
        nodes = []
        cur: _State | None = key
        while cur is not None:
            nodes.append((cur[0], self.best[cur]))
            cur = self.parent[cur]
        nodes.reverse()
        cells = [nodes[0][0]]
        for cell, arrive in nodes[1:]:
            # Wait where we are until one step before the arrival, then move.
            cells.extend([cells[-1]] * (arrive - t0 - len(cells)))
            cells.append(cell)
        times = []
        pos = 0
        for goal in self.goals[:-1]:
            pos = cells.index(goal, pos)
            times.append(t0 + pos)
        times.append(t0 + len(cells) - 1)
        return cells, times


def _swaps(table: ReservationTable, cell: int, nxt: int, arrive: int) -> bool:
    """Whether the robot in ``nxt`` at ``arrive - 1`` is in ``cell`` at ``arrive``."""
    other = table.occupant(nxt, arrive - 1)
    return other >= 0 and table.occupant(cell, arrive) == other
