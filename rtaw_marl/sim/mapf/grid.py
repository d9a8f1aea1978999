"""The grid every multi-robot planner works on, with its one cell encoding.

A cell ``(x, y)`` (``x`` the column, ``y`` the row, as everywhere in rtaw_marl) is the
flat index ``y * width + x``. Planners, reservation tables and fleets exchange cells
only in this encoding; ``(x, y)`` appears only at the edges (tasks coming in, schedules
going out), converted by :meth:`Grid.cell` and :meth:`Grid.xy`.

Distance fields (4-connected BFS distances to a cell, ``-1`` where unreachable) come
from the compiled kernel of :mod:`rtaw_marl.sim._bfs` and are cached: planners ask for
the field of the same goal cells again and again.
"""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Iterable

import numpy as np

from rtaw_marl.errors import LayoutError
from rtaw_marl.sim._bfs import bfs_fields
from rtaw_marl.sim.layout import Layout

__all__ = ["Grid"]


class Grid:
    """Width, height and free cells of a 4-connected grid, with cached distance fields.

    The grid itself never changes; only the field cache does, and it affects no result.

    Args:
        free: ``bool [H, W]``; ``True`` marks a traversable cell.
        cache_mb: Memory budget of the distance-field cache; least recently used fields
            are evicted beyond it (at least 64 fields are kept).
    """

    def __init__(self, free: np.ndarray, cache_mb: float = 64.0) -> None:
        mask = np.array(free, dtype=bool)
        if mask.ndim != 2 or mask.size == 0:
            raise LayoutError(f"a grid needs a non-empty 2-D free mask, got shape {mask.shape}")
        mask.flags.writeable = False
        self._free = mask
        self.height, self.width = (int(s) for s in mask.shape)
        #: Number of cells ``H * W``; cells are ``0 .. size - 1``.
        self.size = self.height * self.width
        self._free_list: list[bool] = mask.ravel().tolist()
        # The BFS kernel wants a blocked one-cell border so it never bounds-checks.
        self._stride = self.width + 2
        padded = np.zeros((self.height + 2, self._stride), dtype=np.bool_)
        padded[1:-1, 1:-1] = mask
        self._padded = padded.ravel()
        self._neighbours: list[list[int] | None] = [None] * self.size
        self._capacity = max(64, int(cache_mb * 2**20 // (4 * self.size)))
        self._fields: OrderedDict[int, np.ndarray] = OrderedDict()

    @classmethod
    def from_layout(cls, layout: Layout) -> Grid:
        """The free cells of ``layout``."""
        return cls(~layout.obstacles)

    # ------------------------------------------------------------------ encoding
    @property
    def free(self) -> np.ndarray:
        """``bool [H, W]`` read-only free mask."""
        return self._free

    def cell(self, x: int, y: int) -> int:
        """The cell of column ``x``, row ``y``."""
        return int(y) * self.width + int(x)

    def cells(self, xy: np.ndarray) -> np.ndarray:
        """Cells ``int64 [...]`` of the coordinates ``xy [..., 2]``."""
        xy = np.asarray(xy, dtype=np.int64)
        return xy[..., 1] * self.width + xy[..., 0]

    def xy(self, cell: int) -> tuple[int, int]:
        """The ``(x, y)`` of ``cell``."""
        y, x = divmod(int(cell), self.width)
        return x, y

    def xys(self, cells: np.ndarray) -> np.ndarray:
        """Coordinates ``int64 [..., 2]`` of ``cells [...]``."""
        cells = np.asarray(cells, dtype=np.int64)
        return np.stack([cells % self.width, cells // self.width], axis=-1)

    def is_free(self, cell: int) -> bool:
        """Whether ``cell`` is traversable."""
        return self._free_list[cell]

    def neighbours(self, cell: int) -> list[int]:
        """The free 4-neighbours of ``cell``: right, left, below, above (in that order).

        The order is part of the planners' tie-breaking, so it never changes.
        """
        out = self._neighbours[cell]
        if out is None:
            x, free, w = cell % self.width, self._free_list, self.width
            out = []
            if x + 1 < w and free[cell + 1]:
                out.append(cell + 1)
            if x > 0 and free[cell - 1]:
                out.append(cell - 1)
            if cell + w < self.size and free[cell + w]:
                out.append(cell + w)
            if cell >= w and free[cell - w]:
                out.append(cell - w)
            self._neighbours[cell] = out
        return out

    # ------------------------------------------------------------------ distances
    def field(self, cell: int) -> np.ndarray:
        """4-connected distances ``int32 [size]`` to ``cell``; ``-1`` where unreachable.

        Cached; do not modify the returned array.
        """
        row = self._fields.get(cell)
        if row is not None:
            self._fields.move_to_end(cell)
            return row
        row = self._flood(self._padded, cell)
        row.flags.writeable = False
        self._fields[cell] = row
        if len(self._fields) > self._capacity:
            self._fields.popitem(last=False)
        return row

    def distance(self, a: int, b: int) -> int:
        """Shortest-path length from ``a`` to ``b``.

        Raises:
            LayoutError: ``b`` cannot be reached from ``a``.
        """
        d = int(self.field(b)[a])
        if d < 0:
            (ax, ay), (bx, by) = self.xy(a), self.xy(b)
            raise LayoutError(f"no path from (x={ax}, y={ay}) to (x={bx}, y={by})")
        return d

    def path(self, a: int, b: int) -> list[int]:
        """Cells of one shortest path from ``a`` to ``b``, both ends included.

        At each step the first neighbour (in :meth:`neighbours` order) one step closer to
        ``b`` is taken, so the path is deterministic.
        """
        field = self.field(b)
        self.distance(a, b)  # raises when unreachable
        cells = [a]
        cur = a
        while field[cur] > 0:
            closer = field[cur] - 1
            cur = next(n for n in self.neighbours(cur) if field[n] == closer)
            cells.append(cur)
        return cells

    def reachable(self, start: int, walls: Iterable[int] = ()) -> np.ndarray:
        """``bool [size]``: cells reachable from ``start`` with ``walls`` blocked as well.

        ``start`` itself counts as free even when it is one of ``walls``.
        """
        padded = self._padded.copy()
        walls = np.fromiter(walls, dtype=np.int64)
        padded[(walls // self.width + 1) * self._stride + walls % self.width + 1] = False
        return self._flood(padded, start, force_start=True) >= 0

    def _flood(self, padded: np.ndarray, cell: int, force_start: bool = False) -> np.ndarray:
        """BFS distances ``int32 [size]`` from ``cell`` on a padded free mask."""
        y, x = divmod(int(cell), self.width)
        source = (y + 1) * self._stride + x + 1
        if force_start:
            padded[source] = True
        out = np.empty((1, padded.size), dtype=np.int32)
        bfs_fields(padded, self._stride, np.array([source], dtype=np.int64), out)
        return np.ascontiguousarray(
            out[0].reshape(self.height + 2, self._stride)[1:-1, 1:-1]
        ).ravel()
