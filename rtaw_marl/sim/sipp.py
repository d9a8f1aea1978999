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
from rtaw_marl.sim._bfs import bfs_fields
from rtaw_marl.sim.reservations import INF, ReservationTable

__all__ = ["sipp_plan"]


def sipp_plan(
    table: ReservationTable,
    free: Sequence[bool],
    width: int,
    start: int,
    t0: int,
    goals: Sequence[int],
    fields: Sequence[np.ndarray],
    deadline: float,
    blockers: set[int] | None = None,
) -> tuple[list[int], list[int]] | None:
    """Earliest-arrival path from ``start`` at ``t0`` through ``goals`` in order.

    Args:
        table: Reservations of all other robots (the planning robot holds nothing from
            ``t0`` on).
        free: Flat traversable mask of the padded grid (border cells blocked).
        width: Row length of the padded grid.
        start: Flat start cell, occupied by the robot at ``t0``.
        t0: Start time.
        goals: Flat goal cells, at least one; the robot holds the last one afterwards.
        fields: Per goal, the single-robot distance field ``int32 [cells]`` to it.
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
    last = len(goals) - 1
    final = goals[last]
    if any(int(f[start]) < 0 for f in fields):
        return None
    if table.holder(final) >= 0:
        if blockers is not None:
            blockers.add(final)
        return None
    earliest = t0
    for k, goal in enumerate(goals[:last]):
        # A goal held forever from some time on must be reached before.
        earliest += int(fields[k][start if k == 0 else goals[k - 1]])
        safe = table.safe_intervals(goal)
        if table.holder(goal) >= 0 and (not safe or earliest > safe[-1][1]):
            if blockers is not None:
                blockers.add(goal)
            return None
    if _walled_in(table, free, width, start, t0, goals, blockers):
        return None
    # rest[k]: distance still to cover after reaching goal k.
    rest = [0] * len(goals)
    for k in range(last - 1, -1, -1):
        rest[k] = rest[k + 1] + int(fields[k + 1][goals[k]])
    offsets = (1, -1, width, -width)

    intervals = table.safe_intervals(start)
    i0 = next((i for i, (a, b) in enumerate(intervals) if a <= t0 <= b), None)
    if i0 is None:
        raise AssertionError(f"start cell {start} is reserved at t={t0}")
    k0 = 0
    while k0 < last and goals[k0] == start:
        k0 += 1
    best: dict[tuple[int, int, int], int] = {(start, i0, k0): t0}
    parent: dict[tuple[int, int, int], tuple[int, int, int] | None] = {(start, i0, k0): None}
    h0 = int(fields[k0][start]) + rest[k0]
    heap = [(t0 + h0, -t0, start, i0, k0)]
    pops = 0
    while heap:
        _, neg_g, cell, i, k = heapq.heappop(heap)
        g = -neg_g
        key = (cell, i, k)
        if best[key] < g:
            continue
        end = table.safe_intervals(cell)[i][1]
        if k == last and cell == final and end == INF:
            return _reconstruct(key, best, parent, goals, t0)
        pops += 1
        if (pops & 511) == 1 and time.perf_counter() > deadline:
            raise PlanningTimeout(f"SIPP ran past its time limit after {pops} expansions")
        field = fields[k]
        for off in offsets:
            nxt = cell + off
            if not free[nxt] or int(field[nxt]) < 0:
                continue
            for j, (a, b) in enumerate(table.safe_intervals(nxt)):
                if a > end + 1:
                    break
                if b < g + 1:
                    continue
                arrive = max(g + 1, a)
                # Leaving one step later avoids a swap with a robot moving nxt -> cell.
                while arrive <= min(b, end + 1) and _swaps(table, cell, nxt, arrive):
                    arrive += 1
                if arrive > min(b, end + 1):
                    continue
                k2 = k
                while k2 < last and goals[k2] == nxt:
                    k2 += 1
                nkey = (nxt, j, k2)
                if arrive < best.get(nkey, INF):
                    best[nkey] = arrive
                    parent[nkey] = key
                    h = int(fields[k2][nxt]) + rest[k2]
                    heapq.heappush(heap, (arrive + h, -arrive, nxt, j, k2))
    if blockers is not None:
        explored = {cell for cell, _, _ in best}
        blockers.update(
            nxt
            for cell in explored
            for nxt in (cell + off for off in offsets)
            if free[nxt] and table.holder(nxt) >= 0
        )
    return None


def _walled_in(
    table: ReservationTable,
    free: Sequence[bool],
    width: int,
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
    grid = np.asarray(free, dtype=np.bool_)
    grid[parked] = False
    grid[start] = True
    reach = np.empty((1, grid.size), dtype=np.int32)
    bfs_fields(grid, width, np.array([start], dtype=np.int64), reach)
    if all(reach[0, g] >= 0 for g in goals):
        return False
    if blockers is not None:
        inside = np.flatnonzero(reach[0] >= 0)
        around = np.concatenate([inside + 1, inside - 1, inside + width, inside - width])
        cells = np.asarray(parked)
        blockers.update(cells[np.isin(cells, around)].tolist())
    return True


def _swaps(table: ReservationTable, cell: int, nxt: int, arrive: int) -> bool:
    other = table.occupant(nxt, arrive - 1)
    return other >= 0 and table.occupant(cell, arrive) == other


def _reconstruct(
    key: tuple[int, int, int],
    best: dict[tuple[int, int, int], int],
    parent: dict[tuple[int, int, int], tuple[int, int, int] | None],
    goals: Sequence[int],
    t0: int,
) -> tuple[list[int], list[int]]:
    nodes = []
    cur: tuple[int, int, int] | None = key
    while cur is not None:
        nodes.append((cur[0], best[cur]))
        cur = parent[cur]
    nodes.reverse()
    cells = [nodes[0][0]]
    for cell, arrive in nodes[1:]:
        # Wait where we are until one step before the arrival, then move.
        cells.extend([cells[-1]] * (arrive - t0 - len(cells)))
        cells.append(cell)
    times = []
    pos = 0
    for goal in goals[:-1]:
        pos = cells.index(goal, pos)
        times.append(t0 + pos)
    times.append(t0 + len(cells) - 1)
    return cells, times
