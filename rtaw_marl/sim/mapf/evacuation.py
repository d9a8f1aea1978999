"""Where to move robots that stand in another robot's way.

A fleet moves robots that will not move by themselves (deferred robots, and idle ones
once the last task is assigned) off a blocked robot's route, to the nearest cells that
are nobody's goal or parking cell. These helpers answer the two questions involved,
on the grid alone: which cells a route covers, and which free cells are nearest.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Iterable, Sequence

import numpy as np

from rtaw_marl.sim.mapf.grid import Grid

__all__ = ["parking_cells", "route_cells", "taken_cells"]


def route_cells(grid: Grid, here: int, goals: Sequence[int], wide: bool = False) -> set[int]:
    """Cells of a single-robot shortest route from ``here`` through ``goals`` in order.

    Args:
        grid: The grid.
        here: Start cell.
        goals: Goal cells, visited in order.
        wide: Cover every shortest route: the cells whose distances from and to the
            ends of a leg add up to its length. Otherwise one route (:meth:`Grid.path`).
    """
    cells = {here}
    for goal in goals:
        if wide:
            da, db = grid.field(here), grid.field(goal)
            on = (da >= 0) & (da + db == da[goal])
            cells.update(np.flatnonzero(on).tolist())
        else:
            cells.update(grid.path(here, goal))
        here = goal
    return cells


def parking_cells(grid: Grid, start: int, avoid: set[int], count: int = 6) -> list[int]:
    """The nearest free cells from ``start`` (BFS order) not in ``avoid``.

    The search stops once ``count`` cells are found, after the cell being expanded, so
    a few more may be returned.
    """
    seen, queue, found = {start}, deque([start]), []
    while queue and len(found) < count:
        cell = queue.popleft()
        for nxt in grid.neighbours(cell):
            if nxt not in seen:
                seen.add(nxt)
                queue.append(nxt)
                if nxt not in avoid:
                    found.append(nxt)
    return found


def taken_cells(ends: Iterable[int], goals: Iterable[Iterable[int]]) -> set[int]:
    """Cells nobody may park on: where robots end up (``ends``) and every robot's goals."""
    taken = set(ends)
    for cells in goals:
        taken.update(cells)
    return taken
