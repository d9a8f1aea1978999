"""Distance models: travel distances between cells of a layout.

A ``navigator=`` option is a distance model (the distances the policies observe, here)
plus an executor (how assigned robots travel: :mod:`rtaw_marl.sim.execution`). A
distance model answers two questions for the simulator:

* the distance between pairs or sets of cells (:meth:`DistanceModel.distance`,
  :meth:`DistanceModel.distance_matrix`), and
* the distances from any robot cells to the ``N`` task origins currently queued,
  through a mutable :class:`TargetSlots` object kept in step with the queue. This is
  the per-decision hot path: one gather, no Python loop over robots.

Robots move one cell per second, so distances are travel times in seconds.

``direct``: :class:`EuclideanDistance`
    Euclidean distance, obstacles ignored (the paper's "Direct" navigation).
``astar``: :class:`GridDistance`
    True 4-connected shortest paths. Distances come from per-target BFS distance
    fields (a BFS from the target is an A* with the exact heuristic) computed by a
    small compiled kernel and kept in an LRU cache; paths are recovered by descending
    the field. A pair of cells in different connected regions is an error.

How robots then travel (independently, or on a
shared grid where they wait for each other: ``sipp``, ``cbs``, which measure distances
with ``astar``) is the simulator's :class:`~rtaw_marl.sim.execution.Executor`.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections import OrderedDict
from collections.abc import Callable

import numpy as np

from rtaw_marl.errors import LayoutError
from rtaw_marl.sim._bfs import bfs_fields
from rtaw_marl.sim._slot_kernels import (
    euclidean_from,
    euclidean_refresh,
    field_gather,
    field_refresh,
)
from rtaw_marl.sim.layout import Layout

__all__ = [
    "SLOT_FIELDS_BYTES",
    "DistanceModel",
    "EuclideanDistance",
    "GridDistance",
    "TargetSlots",
]

#: Up to this many targets, ``GridDistance.distance_matrix`` reads each cached field in
#: place; beyond, it stacks chunks of fields (one gather instead of a loop per target).
_GATHER_COLUMNS = 64
#: Largest dense copy of the queue slots' distance fields (``N x cells x 4`` bytes).
SLOT_FIELDS_BYTES = 256 * 2**20


class TargetSlots(ABC):
    """``N`` mutable target cells; distances from arbitrary cells to all of them."""

    def __init__(self, size: int) -> None:
        self.size = size

    @abstractmethod
    def set(self, slot: int, x: int, y: int) -> None:
        """Make cell ``(x, y)`` the target of ``slot``."""

    @abstractmethod
    def distances_from(self, xy: np.ndarray, slots: np.ndarray | None = None) -> np.ndarray:
        """Distances ``float64 [P, N]`` from each cell of ``xy [P, 2]`` to each slot (to
        the slots ``int [K]`` only when given: ``[P, K]``)."""

    def distances_from_one(self, x: int, y: int) -> np.ndarray:
        """Distances ``float64 [N]`` from cell ``(x, y)`` to each slot."""
        return self.distances_from(np.array([[x, y]]))[0]

    def refresh(self, xy: np.ndarray, out: np.ndarray, rows: np.ndarray, cols: np.ndarray) -> None:
        """Recompute rows ``rows int [R]`` and columns ``cols int [C]`` of ``out``,
        :meth:`distances_from` ``(xy)``'s ``float64 [P, N]`` matrix, in place (after
        the cells ``xy[rows]`` or the targets of slots ``cols`` changed)."""
        if len(rows):
            out[rows] = self.distances_from(xy[rows])
        if len(cols):
            out[:, cols] = self.distances_from(xy, cols)

    @abstractmethod
    def distance_to(self, slot: int, x: int, y: int) -> float:
        """Distance from cell ``(x, y)`` to the target of ``slot``."""


class DistanceModel(ABC):
    """Travel distances on one layout."""

    name: str = ""

    def __init__(self, layout: Layout) -> None:
        self.layout = layout

    @abstractmethod
    def distance(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """Row-wise distances ``float64 [K]`` from ``a [K, 2]`` to ``b [K, 2]``."""

    @abstractmethod
    def distance_matrix(self, sources: np.ndarray, targets: np.ndarray) -> np.ndarray:
        """Distances ``float64 [P, K]`` from every source ``[P, 2]`` to every target ``[K, 2]``."""

    @abstractmethod
    def target_slots(self, size: int) -> TargetSlots:
        """A new :class:`TargetSlots` with ``size`` slots bound to this distance model."""

    @abstractmethod
    def path(self, a: tuple[int, int], b: tuple[int, int]) -> np.ndarray:
        """Cells ``int64 [L, 2]`` visited from ``a`` to ``b``, both ends included."""

    def check_connected(self, cells: np.ndarray, what: str | Callable[[int], str]) -> None:
        """Raise :class:`LayoutError` unless all ``cells [K, 2]`` are mutually reachable.

        The base distance model ignores obstacles, so every pair is reachable.

        Args:
            cells: ``(x, y)`` rows.
            what: How to name cell ``i`` in the message: a word (``"cell"`` gives
                ``cell 3``) or a function of ``i`` (``origin of task 1``).
        """
        del cells, what


class EuclideanDistance(DistanceModel):
    """Euclidean distances; obstacles are ignored (the paper's "Direct" setting)."""

    name = "direct"

    def distance(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        d = np.asarray(a, dtype=np.float64) - np.asarray(b, dtype=np.float64)
        return np.hypot(d[..., 0], d[..., 1])

    def distance_matrix(self, sources: np.ndarray, targets: np.ndarray) -> np.ndarray:
        s = np.asarray(sources, dtype=np.float64)[:, None, :]
        t = np.asarray(targets, dtype=np.float64)[None, :, :]
        return np.hypot(s[..., 0] - t[..., 0], s[..., 1] - t[..., 1])

    def target_slots(self, size: int) -> TargetSlots:
        return _DirectSlots(size)

    def path(self, a: tuple[int, int], b: tuple[int, int]) -> np.ndarray:
        if tuple(a) == tuple(b):
            return np.array([a], dtype=np.int64)
        return np.array([a, b], dtype=np.int64)


class _DirectSlots(TargetSlots):
    def __init__(self, size: int) -> None:
        super().__init__(size)
        self._xy = np.zeros((size, 2), dtype=np.float64)

    def set(self, slot: int, x: int, y: int) -> None:
        self._xy[slot, 0] = x
        self._xy[slot, 1] = y

    def distances_from(self, xy: np.ndarray, slots: np.ndarray | None = None) -> np.ndarray:
        xy = np.asarray(xy)
        if xy.dtype != np.int64:
            xy = xy.astype(np.float64)
        targets = self._xy if slots is None else self._xy[np.asarray(slots)]
        out = np.empty((len(xy), len(targets)), dtype=np.float64)
        euclidean_from(xy.reshape(-1, 2), targets, out)
        return out

    def distances_from_one(self, x: int, y: int) -> np.ndarray:
        return np.hypot(x - self._xy[:, 0], y - self._xy[:, 1])

    def refresh(self, xy: np.ndarray, out: np.ndarray, rows: np.ndarray, cols: np.ndarray) -> None:
        euclidean_refresh(xy, self._xy, rows, cols, out)

    def distance_to(self, slot: int, x: int, y: int) -> float:
        return float(np.hypot(x - self._xy[slot, 0], y - self._xy[slot, 1]))


class GridDistance(DistanceModel):
    """4-connected shortest paths from cached per-target BFS distance fields.

    Fields live on the grid padded by one blocked border cell, so the BFS kernel needs
    no bounds checks; ``_padded_index`` maps ``(x, y)`` to that layout. A field is
    ``int32 [(H + 2) * (W + 2)]`` with ``-1`` on unreachable cells.

    Args:
        layout: The grid.
        cache_mb: Memory budget of the field cache; least recently used fields are
            evicted beyond it.
    """

    name = "astar"

    def __init__(self, layout: Layout, cache_mb: float = 256.0) -> None:
        super().__init__(layout)
        self._wp = layout.width + 2
        free = np.zeros((layout.height + 2, self._wp), dtype=np.bool_)
        free[1:-1, 1:-1] = ~layout.obstacles
        self._free_padded = free.ravel()
        field_bytes = self._free_padded.size * 4
        self._capacity = max(64, int(cache_mb * 2**20 // field_bytes))
        self._cache: OrderedDict[int, np.ndarray] = OrderedDict()
        self.fields_computed = 0

    def _padded_index(self, xy: np.ndarray) -> np.ndarray:
        xy = np.asarray(xy, dtype=np.int64)
        return (xy[..., 1] + 1) * self._wp + (xy[..., 0] + 1)

    def fields(self, targets: np.ndarray) -> np.ndarray:
        """Distance fields ``int32 [K, (H + 2) * (W + 2)]`` of the cells ``targets [K, 2]``.

        Missing fields are computed in one batched kernel call and cached.
        """
        keys = self._padded_index(targets).reshape(-1).tolist()
        self._compute_missing(keys)
        rows = [self._cache[k] for k in keys]
        self._evict()
        return np.stack(rows) if rows else np.empty((0, self._free_padded.size), np.int32)

    def field(self, x: int, y: int) -> np.ndarray:
        """The distance field ``int32 [(H + 2) * (W + 2)]`` of one target cell."""
        key = (int(y) + 1) * self._wp + int(x) + 1
        row = self._cache.get(key)
        if row is None:
            # One search straight into the cache (no stacking of a batch of one).
            out = np.empty((1, self._free_padded.size), dtype=np.int32)
            bfs_fields(self._free_padded, self._wp, np.array([key], dtype=np.int64), out)
            self.fields_computed += 1
            row = self._cache[key] = out[0]
            if len(self._cache) > self._capacity:
                self._cache.popitem(last=False)
            return row
        self._cache.move_to_end(key)
        return row

    def distance(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        a = np.asarray(a, dtype=np.int64).reshape(-1, 2)
        b = np.asarray(b, dtype=np.int64).reshape(-1, 2)
        out = np.empty(len(a), dtype=np.float64)
        src = self._padded_index(a)
        # Grouped by target: each distinct target costs one field lookup, read in place
        # (stacking thousands of fields of a large map would copy gigabytes).
        uniq, inverse = np.unique(self._padded_index(b), return_inverse=True)
        order = np.argsort(inverse, kind="stable")
        bounds = np.searchsorted(inverse[order], np.arange(len(uniq) + 1))
        step = max(1, self._capacity // 2)
        for start in range(0, len(uniq), step):
            keys = uniq[start : start + step].tolist()
            self._compute_missing(keys)
            for j, key in enumerate(keys, start):
                rows = order[bounds[j] : bounds[j + 1]]
                out[rows] = self._cache[key][src[rows]]
            self._evict()
        return self._checked(out, a, b)

    def _compute_missing(self, keys: list[int]) -> None:
        """Put the fields of the padded cells ``keys`` in the cache (one kernel call for
        the missing ones) and mark them recently used; :meth:`_evict` trims it after."""
        missing = [k for k in dict.fromkeys(keys) if k not in self._cache]
        if missing:
            out = np.empty((len(missing), self._free_padded.size), dtype=np.int32)
            bfs_fields(self._free_padded, self._wp, np.asarray(missing, dtype=np.int64), out)
            self.fields_computed += len(missing)
            for k, row in zip(missing, out, strict=True):
                self._cache[k] = row
        for k in keys:
            self._cache.move_to_end(k)

    def _evict(self) -> None:
        while len(self._cache) > self._capacity:
            self._cache.popitem(last=False)

    def distance_matrix(self, sources: np.ndarray, targets: np.ndarray) -> np.ndarray:
        sources = np.asarray(sources, dtype=np.int64).reshape(-1, 2)
        targets = np.asarray(targets, dtype=np.int64).reshape(-1, 2)
        src = self._padded_index(sources)
        d = np.empty((len(sources), len(targets)), dtype=np.float64)
        step = max(1, self._capacity // 2)
        if len(targets) <= _GATHER_COLUMNS or len(sources) * 8 < self._free_padded.size:
            # Few targets (a rollout's queue) or few sources (a scheduler's robots against
            # its pool): gather from each cached field in place; stacking whole fields
            # first (2.6 MB for 10 at 256x256) to read a few entries of each costs more.
            keys = self._padded_index(targets).tolist()
            for start in range(0, len(keys), step):
                chunk = keys[start : start + step]
                self._compute_missing(chunk)
                for j, key in enumerate(chunk, start):
                    d[:, j] = self._cache[key][src]
                self._evict()
        else:
            # Chunks of targets bound the memory of stacked fields (260 KiB each at 256^2).
            for start in range(0, len(targets), step):
                d[:, start : start + step] = self.fields(targets[start : start + step])[:, src].T
        if (d < 0).any():
            i, j = np.argwhere(d < 0)[0]
            self._checked(np.array([-1.0]), sources[i : i + 1], targets[j : j + 1])
        return d

    def target_slots(self, size: int) -> TargetSlots:
        # A dense copy of every slot's field makes MPDM's query one gather, but LoRR's
        # pools (15,000 slots on a 500x140 map) would take gigabytes: beyond
        # SLOT_FIELDS_BYTES the slots keep their cells and a query gathers from the
        # fields of whichever side is smaller (distances are symmetric).
        if size * self._free_padded.size * 4 <= SLOT_FIELDS_BYTES:
            return _FieldSlots(self, size)
        return _CellSlots(self, size)

    def path(self, a: tuple[int, int], b: tuple[int, int]) -> np.ndarray:
        field = self.field(*b)
        cur = int(self._padded_index(np.array(a)))
        if field[cur] < 0:
            self._checked(np.array([-1.0]), np.array([a]), np.array([b]))
        cells = [cur]
        offsets = (1, -1, self._wp, -self._wp)
        while field[cur] > 0:
            # Any neighbour one step closer to b lies on a shortest path.
            cur = next(cur + o for o in offsets if field[cur + o] == field[cur] - 1)
            cells.append(cur)
        cells_arr = np.asarray(cells)
        return np.stack([cells_arr % self._wp - 1, cells_arr // self._wp - 1], axis=1)

    def check_connected(self, cells: np.ndarray, what: str | Callable[[int], str]) -> None:
        cells = np.asarray(cells, dtype=np.int64).reshape(-1, 2)
        if cells.size == 0 or self.layout.num_components == 1:
            return
        labels = self.layout.component_labels[cells[:, 1], cells[:, 0]]
        # Blame the cells outside the region most of them share (ties: the larger
        # region), not every cell but the first: a walled-in first task must not make
        # all the others look unreachable.
        regions, counts = np.unique(labels, return_counts=True)
        sizes = np.bincount(self.layout.component_labels.ravel())[regions]
        main = regions[np.lexsort((sizes, counts))[-1]]
        bad = np.flatnonzero(labels != main)
        if bad.size:
            i, j = int(bad[0]), int(np.flatnonzero(labels == main)[0])
            name = what(i) if callable(what) else f"{what} {i}"
            raise LayoutError(
                f"{name} at (x={int(cells[i, 0])}, y={int(cells[i, 1])}) cannot be reached "
                f"from the other cells, e.g. (x={int(cells[j, 0])}, y={int(cells[j, 1])}), on "
                f"layout {self.layout.name!r}: they lie in different connected regions"
            )

    def _checked(self, d: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        if (d < 0).any():
            i = int(np.flatnonzero(d < 0)[0])
            raise LayoutError(
                f"no path from (x={int(a[i, 0])}, y={int(a[i, 1])}) to "
                f"(x={int(b[i, 0])}, y={int(b[i, 1])}) on layout {self.layout.name!r}"
            )
        return d


class _FieldSlots(TargetSlots):
    """Slot targets as a dense ``[N, cells]`` copy of their fields, so a query is one gather."""

    def __init__(self, distance_model: GridDistance, size: int) -> None:
        super().__init__(size)
        self._model = distance_model
        self._fields = np.zeros((size, distance_model._free_padded.size), dtype=np.int32)
        self._rows = np.arange(size)

    def set(self, slot: int, x: int, y: int) -> None:
        self._fields[slot] = self._model.field(x, y)

    def distances_from(self, xy: np.ndarray, slots: np.ndarray | None = None) -> np.ndarray:
        xy = np.asarray(xy, dtype=np.int64).reshape(-1, 2)
        rows = self._rows if slots is None else np.asarray(slots, dtype=np.int64)
        # One gather of the [P, K] entries (never a copy of K whole fields).
        out = np.empty((len(xy), len(rows)), dtype=np.float64)
        field_gather(self._fields, rows, xy, self._model._wp, out)
        return out

    def distances_from_one(self, x: int, y: int) -> np.ndarray:
        return self._fields[:, (y + 1) * self._model._wp + x + 1].astype(np.float64)

    def refresh(self, xy: np.ndarray, out: np.ndarray, rows: np.ndarray, cols: np.ndarray) -> None:
        field_refresh(self._fields, xy, self._model._wp, rows, cols, out)

    def distance_to(self, slot: int, x: int, y: int) -> float:
        d = int(self._fields[slot, (y + 1) * self._model._wp + x + 1])
        if d < 0:
            raise LayoutError(
                f"no path from (x={x}, y={y}) to a queued task origin on layout "
                f"{self._model.layout.name!r}"
            )
        return float(d)


class _CellSlots(TargetSlots):
    """Slot targets as cells only; a query computes (or takes from the distance model's
    cache) the fields of its smaller side: the ``P`` sources, or the ``K`` targets."""

    def __init__(self, distance_model: GridDistance, size: int) -> None:
        super().__init__(size)
        self._model = distance_model
        self._cells = np.zeros(size, dtype=np.int64)  # padded index of each target
        self._xy = np.zeros((size, 2), dtype=np.int64)

    def set(self, slot: int, x: int, y: int) -> None:
        self._cells[slot] = (y + 1) * self._model._wp + x + 1
        self._xy[slot] = (x, y)

    def distances_from(self, xy: np.ndarray, slots: np.ndarray | None = None) -> np.ndarray:
        xy = np.asarray(xy, dtype=np.int64).reshape(-1, 2)
        chosen = slice(None) if slots is None else np.asarray(slots)
        cells = self._cells[chosen]
        if len(xy) <= len(cells):
            # Row by row: stacking P whole fields first would copy P x cells entries.
            out = np.empty((len(xy), len(cells)), dtype=np.float64)
            for i, (x, y) in enumerate(xy.tolist()):
                out[i] = self._model.field(x, y)[cells]
            return out
        # Column by column, each field read in place: stacking K whole fields of a large
        # map first would copy K x cells entries (113 MB for 400 on warehouse_large).
        model, src = self._model, self._model._padded_index(xy)
        keys = cells.tolist()
        model._compute_missing(keys)  # the missing fields in one kernel call
        out = np.empty((len(keys), len(xy)), dtype=np.float64)
        for j, key in enumerate(keys):
            out[j] = model._cache[key][src]
        model._evict()
        return out.T

    def distances_from_one(self, x: int, y: int) -> np.ndarray:
        return self._model.field(x, y)[self._cells].astype(np.float64)

    def distance_to(self, slot: int, x: int, y: int) -> float:
        d = int(self._model.field(x, y)[self._cells[slot]])
        if d < 0:
            raise LayoutError(
                f"no path from (x={x}, y={y}) to a queued task origin on layout "
                f"{self._model.layout.name!r}"
            )
        return float(d)
