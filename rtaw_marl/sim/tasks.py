"""Task streams: where pickup -> delivery tasks come from.

A task is an ``int64 [4]`` row ``(ox, oy, dx, dy)``: origin (pickup) and destination
(delivery) cells. A stream draws an episode's tasks up front, in arrival order, from a
``numpy.random.Generator`` seeded by the episode seed, so every policy sees the same
tasks for the same seed whatever it decides.

``random``
    Origin and destination uniform over the layout's main connected region, distinct.
``designated``
    Origin drawn from a Gaussian (``sigma`` cells) around a pickup centre chosen
    uniformly, destination likewise around a delivery centre. Draws are rounded to the
    nearest cell; draws off the grid, on obstacles or outside the main region are
    redrawn (a truncated Gaussian). Defaults are the original RTAW code's five centres,
    written for its 60x60 area and scaled to other layouts (:func:`default_centres`), so
    they spread over the whole map; given centres are the layout's own cells.
``clustered``
    Like ``designated`` but around ``num_clusters`` centres drawn per episode on free cells.
``stations``
    Origins uniform over the layout's pickup stations, destinations over its delivery
    stations (generated warehouse layouts mark both).
``file``
    A fixed list read from a CSV file with header ``ox,oy,dx,dy``, one task per row in
    arrival order.
``poc`` / ``two_task``
    The paper's appendix settings. ``two_task`` refills every queue slot with the task
    it just lost, so the queue always holds both fixed tasks.
"""

from __future__ import annotations

import csv
from abc import ABC, abstractmethod
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from rtaw_marl.errors import ConfigError, TaskFileError
from rtaw_marl.sim.layout import MAX_COORDINATE, Layout
from rtaw_marl.sim.maps import resolve_path
from rtaw_marl.utils.checks import check_number

__all__ = [
    "AREA_SLACK",
    "DEFAULT_AREA",
    "DEFAULT_CENTRES",
    "POC_TASKS",
    "TWO_TASKS",
    "ClusteredTasks",
    "DesignatedTasks",
    "FixedTasks",
    "RandomTasks",
    "StationTasks",
    "TaskStream",
    "default_centres",
    "load_task_csv",
]

#: Pickup/delivery centres of the original RTAW code, ``(x, y)``, written for its 60x60
#: area (:data:`DEFAULT_AREA`); :func:`default_centres` places them on a layout.
DEFAULT_CENTRES: tuple[tuple[int, int], ...] = ((11, 10), (29, 29), (48, 16), (48, 29), (4, 54))

#: ``(W, H)`` of the area :data:`DEFAULT_CENTRES` are written for.
DEFAULT_AREA: tuple[int, int] = (60, 60)

#: A layout side up to this many cells longer than the area's keeps the default centres as
#: written: the original code drew them unchanged on its 64x64 maps (their 60x60 area
#: inside), so every 60x60 and 64x64 setting keeps the task streams of its shipped results.
AREA_SLACK = 4

#: The paper's proof-of-concept tasks (appendix, Table "task list"), in arrival order.
POC_TASKS: tuple[tuple[int, int, int, int], ...] = (
    (2, 9, 5, 5),
    (4, 4, 0, 0),
    (5, 6, 3, 2),
    (2, 4, 1, 2),
    (0, 5, 7, 1),
)

#: The paper's two-task setting: task A (0,0)->(3,3) and task B (0,0)->(9,9).
TWO_TASKS: tuple[tuple[int, int, int, int], ...] = ((0, 0, 3, 3), (0, 0, 9, 9))

_MAX_REDRAWS = 1000


class TaskStream(ABC):
    """Draws an episode's tasks.

    Attributes:
        refill_same_slot: If true, a queue slot is refilled with a copy of the task it
            just lost instead of the next task of the stream.
        max_tasks: How many tasks the stream can supply, or ``None`` for unbounded.
    """

    refill_same_slot: bool = False
    max_tasks: int | None = None

    @abstractmethod
    def generate(self, rng: np.random.Generator, layout: Layout, count: int) -> np.ndarray:
        """The first ``count`` tasks, ``int64 [count, 4]`` in arrival order."""

    def starts(self, rng: np.random.Generator, layout: Layout, count: int) -> np.ndarray | None:
        """The robots' start cells ``int64 [count, 2]`` that come with the stream (a LoRR
        problem's agent file), or ``None``: random distinct free cells."""
        del rng, layout, count
        return None


class RandomTasks(TaskStream):
    """Origins and destinations uniform over the main connected region, origin != destination."""

    def generate(self, rng: np.random.Generator, layout: Layout, count: int) -> np.ndarray:
        cells = layout.main_cells
        if len(cells) < 2:
            raise ConfigError(f"layout {layout.name!r} needs at least 2 free cells for tasks")
        origin = rng.integers(len(cells), size=count)
        dest = rng.integers(len(cells), size=count)
        same = np.flatnonzero(origin == dest)
        while same.size:
            dest[same] = rng.integers(len(cells), size=same.size)
            same = same[origin[same] == dest[same]]
        return np.concatenate([cells[origin], cells[dest]], axis=1)


class DesignatedTasks(TaskStream):
    """Gaussian pickup and delivery regions around fixed centres.

    Args:
        pickup_centres: ``(x, y)`` centres of the pickup regions, cells of the layout
            used as given; ``None``: :func:`default_centres`, placed on each layout.
        delivery_centres: ``(x, y)`` centres of the delivery regions, likewise.
        sigma: Standard deviation of each region in cells (on every layout size).
    """

    def __init__(
        self,
        pickup_centres: Sequence[Sequence[float]] | None,
        delivery_centres: Sequence[Sequence[float]] | None,
        sigma: float,
    ) -> None:
        #: The given centres ``float64 [K, 2]``, or ``None``: the default ones.
        self.pickup_centres = (
            None if pickup_centres is None else _centres(pickup_centres, "pickup_centres")
        )
        self.delivery_centres = (
            None if delivery_centres is None else _centres(delivery_centres, "delivery_centres")
        )
        check_number("tasks.sigma", sigma, above=0)
        self.sigma = float(sigma)

    def centres(self, layout: Layout) -> tuple[np.ndarray, np.ndarray]:
        """The pickup and delivery centres ``float64 [K, 2]`` used on ``layout``.

        Raises:
            ConfigError: A given centre lies outside ``layout`` (given centres are never
                moved or scaled).
        """
        out = []
        for name, given in (("pickup", self.pickup_centres), ("delivery", self.delivery_centres)):
            if given is None:
                out.append(default_centres(layout))
                continue
            outside = ~layout.in_bounds(np.round(given).astype(np.int64))
            if outside.any():
                c = given[int(np.flatnonzero(outside)[0])]
                raise ConfigError(
                    f"designated {name} centre ({c[0]:g}, {c[1]:g}) is outside layout "
                    f"{layout.name!r} ({layout.width}x{layout.height})"
                )
            out.append(given)
        return out[0], out[1]

    def generate(self, rng: np.random.Generator, layout: Layout, count: int) -> np.ndarray:
        main = np.zeros(layout.obstacles.shape, dtype=bool)
        main[layout.main_cells[:, 1], layout.main_cells[:, 0]] = True
        pickup, delivery = self.centres(layout)
        origin = self._draw(rng, layout, main, pickup, count)
        dest = self._draw(rng, layout, main, delivery, count)
        same = np.flatnonzero((origin == dest).all(axis=1))
        for _ in range(_MAX_REDRAWS):
            if not same.size:
                return np.concatenate([origin, dest], axis=1)
            dest[same] = self._draw(rng, layout, main, delivery, same.size)
            same = same[(origin[same] == dest[same]).all(axis=1)]
        raise ConfigError(
            f"designated tasks: cannot draw a destination different from origin "
            f"({int(origin[same[0], 0])}, {int(origin[same[0], 1])}); widen tasks.sigma"
        )

    def _draw(
        self,
        rng: np.random.Generator,
        layout: Layout,
        main: np.ndarray,
        centres: np.ndarray,
        count: int,
    ) -> np.ndarray:
        which = rng.integers(len(centres), size=count)
        cells = np.empty((count, 2), dtype=np.int64)
        todo = np.arange(count)
        for _ in range(_MAX_REDRAWS):
            draw = np.rint(centres[which[todo]] + rng.normal(0.0, self.sigma, (todo.size, 2)))
            draw = draw.astype(np.int64)
            ok = layout.in_bounds(draw)
            ok[ok] = main[draw[ok, 1], draw[ok, 0]]
            cells[todo[ok]] = draw[ok]
            todo = todo[~ok]
            if not todo.size:
                return cells
        c = centres[which[todo[0]]]
        raise ConfigError(
            f"designated centre ({c[0]:g}, {c[1]:g}) has no reachable free cell within a few "
            f"sigma={self.sigma:g} on layout {layout.name!r}"
        )


def default_centres(layout: Layout) -> np.ndarray:
    """:data:`DEFAULT_CENTRES` placed on ``layout``, ``float64 [5, 2]``.

    Along a side of 60 to 64 cells (:data:`DEFAULT_AREA` plus :data:`AREA_SLACK`: the
    grids the centres were made for) a coordinate stays as written, so those layouts
    keep their task streams. Along any other side it is scaled in proportion, cell
    centre to cell centre (``x' = (x + 0.5) * W / 60 - 0.5``), so the five regions cover
    the same share of a 161x63 map as of a 60x60 one instead of its first 60 columns.
    A scaled centre whose nearest cell is not in the layout's main region (an obstacle, a
    small region) moves to the nearest main-region cell (Euclidean; ties go to the lowest
    row, then the lowest column), so every region has free cells around its centre.

    Raises:
        ConfigError: The layout has no free cell.
    """
    centres = np.array(DEFAULT_CENTRES, dtype=np.float64)
    size = np.array([layout.width, layout.height], dtype=np.float64)
    area = np.array(DEFAULT_AREA, dtype=np.float64)
    keep = (size >= area) & (size <= area + AREA_SLACK)
    if keep.all():
        # Untouched (no snapping either): the streams of 60x60 and 64x64 layouts.
        return centres
    scaled = np.where(keep, centres, (centres + 0.5) * size / area - 0.5)
    cells = layout.main_cells
    if not len(cells):
        raise ConfigError(f"designated tasks: layout {layout.name!r} has no free cell")
    in_main = np.zeros(layout.obstacles.shape, dtype=bool)
    in_main[cells[:, 1], cells[:, 0]] = True
    nearest = np.rint(scaled).astype(np.int64)
    ok = layout.in_bounds(nearest)
    ok[ok] = in_main[nearest[ok, 1], nearest[ok, 0]]
    for i in np.flatnonzero(~ok):
        # main_cells is in row-major order and argmin takes the first minimum: the
        # lowest row, then the lowest column, among equally near cells.
        d2 = ((cells - scaled[i]) ** 2).sum(axis=1)
        scaled[i] = cells[int(d2.argmin())]
    return scaled


class ClusteredTasks(TaskStream):
    """Tasks around ``num_clusters`` centres drawn per episode on free cells.

    Unlike ``designated`` (fixed, configured centres), the clusters move with the episode
    seed. Each origin and destination is drawn like a designated task around a uniformly
    chosen cluster centre.

    Args:
        num_clusters: Number of cluster centres.
        sigma: Standard deviation of each cluster in cells.
    """

    def __init__(self, num_clusters: int, sigma: float) -> None:
        if isinstance(num_clusters, bool) or not isinstance(num_clusters, (int, np.integer)):
            raise ConfigError(f"tasks.num_clusters must be an integer, got {num_clusters!r}")
        if num_clusters < 1:
            raise ConfigError(f"tasks.num_clusters must be >= 1, got {num_clusters}")
        check_number("tasks.sigma", sigma, above=0)
        self.num_clusters = int(num_clusters)
        self.sigma = float(sigma)

    def generate(self, rng: np.random.Generator, layout: Layout, count: int) -> np.ndarray:
        cells = layout.main_cells
        centres = cells[
            rng.choice(len(cells), size=min(self.num_clusters, len(cells)), replace=False)
        ]
        return DesignatedTasks(centres, centres, self.sigma).generate(rng, layout, count)


class StationTasks(TaskStream):
    """Origins uniform over the layout's pickup stations, destinations over its delivery
    stations (layouts from the warehouse generator mark both)."""

    def generate(self, rng: np.random.Generator, layout: Layout, count: int) -> np.ndarray:
        pickup, delivery = layout.station_cells("pickup"), layout.station_cells("delivery")
        for kind, cells in (("pickup", pickup), ("delivery", delivery)):
            if not len(cells):
                raise ConfigError(
                    f"tasks=stations: layout {layout.name!r} marks no reachable {kind} "
                    "stations; use a generated warehouse layout (layout=A..E or warehouse)"
                )
        origin = pickup[rng.integers(len(pickup), size=count)]
        dest = delivery[rng.integers(len(delivery), size=count)]
        return np.concatenate([origin, dest], axis=1)


class FixedTasks(TaskStream):
    """A fixed list of tasks served in order (CSV files, the paper's appendix lists).

    Args:
        tasks: ``[K, 4]`` rows ``(ox, oy, dx, dy)``.
        refill_same_slot: Refill a slot with the task it just lost (the two-task setting);
            the queue length must then equal ``K``.
        name: Label used in error messages.
    """

    def __init__(
        self,
        tasks: Sequence[Sequence[int]] | np.ndarray,
        refill_same_slot: bool = False,
        name: str = "task list",
    ) -> None:
        self.tasks = _task_array(tasks, name)
        self.refill_same_slot = refill_same_slot
        self.max_tasks = None if refill_same_slot else len(self.tasks)
        self.name = name

    def generate(self, rng: np.random.Generator, layout: Layout, count: int) -> np.ndarray:
        layout.check_cells(self.tasks[:, :2], f"{self.name}: origin of task")
        layout.check_cells(self.tasks[:, 2:], f"{self.name}: destination of task")
        if self.refill_same_slot:
            return np.resize(self.tasks, (count, 4))
        if count > len(self.tasks):
            raise ConfigError(
                f"{self.name} holds {len(self.tasks)} tasks but the episode needs {count}; "
                "lower sim.num_tasks (paper mode needs num_tasks + queue_len)"
            )
        return self.tasks[:count].copy()


def load_task_csv(path: str | Path) -> FixedTasks:
    """Read a task list from a CSV file with header ``ox,oy,dx,dy`` (UTF-8; a leading
    byte-order mark, as spreadsheet programs write, is allowed).

    Args:
        path: The file; ``builtin:NAME`` is resolved like every input path
            (:func:`rtaw_marl.sim.maps.resolve_path`), though no task CSV is shipped.

    Raises:
        ConfigError: ``builtin:`` names no shipped map (the message lists them).
        TaskFileError: The file is missing, is not UTF-8 text or not CSV, has no such
            header, or a row is malformed or out of range.
    """
    path = resolve_path(path)
    if not path.is_file():
        raise TaskFileError(f"task file not found: {path}")
    rows: list[list[int]] = []
    lineno = 1
    try:
        # utf-8-sig drops a byte-order mark, which would otherwise glue onto "ox".
        with path.open(encoding="utf-8-sig", newline="") as fh:
            reader = csv.reader(fh)
            first = next(reader, [])
            header = [h.strip().lower() for h in first]
            if header != ["ox", "oy", "dx", "dy"]:
                got = ",".join(first)
                raise TaskFileError(
                    f"{path}: first line must be the header 'ox,oy,dx,dy', got {got[:40]!r}"
                )
            for row in reader:
                lineno = reader.line_num
                if any(cell.strip() for cell in row):
                    rows.append(_task_row(row, f"{path}:{lineno}"))
    except UnicodeDecodeError as exc:
        raise TaskFileError(
            f"{path}: not a UTF-8 text file (byte 0x{exc.object[exc.start]:02x} cannot be "
            "decoded); expected a CSV with header 'ox,oy,dx,dy'"
        ) from None
    except csv.Error as exc:
        raise TaskFileError(f"{path}:{lineno + 1}: not a task CSV ({exc})") from None
    if not rows:
        raise TaskFileError(f"{path}: no tasks")
    return FixedTasks(rows, name=str(path))


def _task_row(row: list[str], where: str) -> list[int]:
    """One CSV row as 4 integer coordinates, each within :data:`MAX_COORDINATE`."""
    try:
        values = [int(cell) for cell in row]
    except ValueError:
        raise TaskFileError(f"{where}: expected 4 integers, got {row}") from None
    if len(values) != 4:
        raise TaskFileError(f"{where}: expected 4 integers, got {row}")
    for value in values:
        if abs(value) > MAX_COORDINATE:
            raise TaskFileError(
                f"{where}: coordinate {value} is out of range (|value| <= {MAX_COORDINATE})"
            )
    return values


def _task_array(tasks: Sequence[Sequence[int]] | np.ndarray, name: str) -> np.ndarray:
    """``tasks`` as ``int64 [K, 4]``, refusing non-integers and coordinates past
    :data:`MAX_COORDINATE` (which a cast to ``int64`` would otherwise wrap silently)."""
    try:
        arr = np.asarray(tasks)
    except ValueError:  # ragged rows
        arr = np.empty(0)
    if arr.ndim != 2 or arr.shape[1] != 4 or len(arr) == 0:
        raise TaskFileError(f"{name}: expected a non-empty list of (ox, oy, dx, dy) rows")
    if arr.dtype.kind not in "iufO":
        raise TaskFileError(f"{name}: task coordinates must be integers, got {arr.dtype}")
    if arr.dtype.kind == "O":
        # Python ints past int64 land here: compare them exactly, one by one.
        for i, value in enumerate(arr.ravel().tolist()):
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                raise TaskFileError(f"{name}: task {i // 4} coordinate {value!r} is not a number")
            if abs(value) > MAX_COORDINATE:
                raise TaskFileError(
                    f"{name}: task {i // 4} coordinate {value} is out of range "
                    f"(|value| <= {MAX_COORDINATE})"
                )
        arr = arr.astype(np.float64)
    if arr.dtype.kind == "f" and not (np.isfinite(arr).all() and (arr == np.round(arr)).all()):
        raise TaskFileError(f"{name}: task coordinates must be integers")
    outside = np.flatnonzero(np.abs(arr.ravel()) > MAX_COORDINATE)
    if outside.size:
        i = int(outside[0])
        raise TaskFileError(
            f"{name}: task {i // 4} coordinate {arr.ravel()[i]:.0f} is out of range "
            f"(|value| <= {MAX_COORDINATE})"
        )
    return arr.astype(np.int64)


def _centres(centres: Sequence[Sequence[float]], key: str) -> np.ndarray:
    try:
        arr = np.asarray(centres, dtype=np.float64)
    except (TypeError, ValueError):
        arr = np.empty(0)
    if arr.ndim != 2 or arr.shape[1] != 2 or len(arr) == 0:
        raise ConfigError(f"tasks.{key} must be a non-empty list of [x, y] pairs")
    if not np.isfinite(arr).all():
        raise ConfigError(f"tasks.{key} must hold finite numbers, got {arr.tolist()}")
    return arr
