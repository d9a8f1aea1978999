"""Warehouse layouts: a boolean obstacle grid and its loaders.

Coordinates everywhere in rtaw_marl are ``(x, y)`` with ``x`` the column and ``y``
the row, both starting at 0 in the top-left corner of the file as written. Arrays
indexed by cell are indexed ``[y, x]``.

Supported files:

* SBPL-style ``.cfg`` (the original RTAW code's layouts): 10 header lines, the last
  one ``environment:``, then ``H`` rows of ``W`` space-separated integers, ``0`` free
  and ``>= obsthresh`` blocked.
* MovingAI ``.map`` (octile): ``key value`` header lines up to ``map``, then ``H``
  lines of ``W`` characters; ``@``, ``T``, ``O`` and ``W`` are blocked, every other
  character is free.
* ASCII ``.txt``/``.grid``: rows of ``.`` (free) and ``@`` (blocked), no header.

Any other extension is an error naming these (:data:`LAYOUT_FORMATS`), rather than a
MovingAI ``.scen`` or a JSON file misread as an ASCII map.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path

import numpy as np
from scipy import ndimage

from rtaw_marl.errors import LayoutError

__all__ = [
    "LAYOUT_FORMATS",
    "MAX_COORDINATE",
    "Layout",
    "check_sizes",
    "load_layout",
    "open_grid",
    "shelf_grid",
]

#: Largest coordinate a task or a robot start may name: no grid is that large, and
#: ``int64`` arithmetic on cells stays exact (a cast would wrap a larger value silently).
MAX_COORDINATE = 2**31 - 1

#: Layout file formats by extension (the loader picks its parser from the extension).
LAYOUT_FORMATS = {
    ".cfg": "SBPL",
    ".map": "MovingAI",
    ".txt": "ASCII",
    ".grid": "ASCII",
}

_BLOCKED_MAP_CHARS = frozenset("@TOW")
_FOUR_CONNECTED = np.array([[0, 1, 0], [1, 1, 1], [0, 1, 0]], dtype=bool)


@dataclass(frozen=True, eq=False)
class Layout:
    """An immutable warehouse grid.

    Attributes:
        obstacles: Boolean array ``[H, W]``; ``True`` marks a blocked cell.
        name: A short label used in reports and renderings.
        pickup: Optional boolean ``[H, W]`` mask of pickup stations (station-based tasks).
        delivery: Optional boolean ``[H, W]`` mask of delivery stations.
    """

    obstacles: np.ndarray
    name: str = "grid"
    pickup: np.ndarray | None = field(default=None, repr=False)
    delivery: np.ndarray | None = field(default=None, repr=False)

    def __post_init__(self) -> None:
        grid = np.asarray(self.obstacles, dtype=bool)
        if grid.ndim != 2 or grid.shape[0] < 1 or grid.shape[1] < 1:
            raise LayoutError(f"layout {self.name!r}: obstacle grid must be 2-D and non-empty")
        if grid.all():
            raise LayoutError(f"layout {self.name!r} has no free cell")
        grid = grid.copy()
        grid.flags.writeable = False
        object.__setattr__(self, "obstacles", grid)
        for kind in ("pickup", "delivery"):
            mask = getattr(self, kind)
            if mask is None:
                continue
            mask = np.asarray(mask, dtype=bool).copy()
            if mask.shape != grid.shape:
                raise LayoutError(
                    f"layout {self.name!r}: {kind} mask is {mask.shape}, grid is {grid.shape}"
                )
            on_obstacle = np.argwhere(mask & grid)
            if len(on_obstacle):
                y, x = on_obstacle[0]
                raise LayoutError(
                    f"layout {self.name!r}: {kind} station at (x={x}, y={y}) is on an obstacle"
                )
            mask.flags.writeable = False
            object.__setattr__(self, kind, mask)

    @property
    def height(self) -> int:
        """Number of rows ``H``."""
        return int(self.obstacles.shape[0])

    @property
    def width(self) -> int:
        """Number of columns ``W``."""
        return int(self.obstacles.shape[1])

    @property
    def scale(self) -> float:
        """Length scale ``max(W, H)`` used to bring coordinates to roughly unit range."""
        return float(max(self.width, self.height))

    @cached_property
    def free_cells(self) -> np.ndarray:
        """All free cells as ``int64 [K, 2]`` ``(x, y)`` rows, in row-major order."""
        ys, xs = np.nonzero(~self.obstacles)
        return np.stack([xs, ys], axis=1).astype(np.int64)

    @cached_property
    def component_labels(self) -> np.ndarray:
        """4-connected component label per cell ``int32 [H, W]`` (0 on obstacles)."""
        labels, _ = ndimage.label(~self.obstacles, structure=_FOUR_CONNECTED)
        return labels.astype(np.int32)

    @cached_property
    def num_components(self) -> int:
        """Number of 4-connected regions of free cells."""
        return int(self.component_labels.max())

    @cached_property
    def main_cells(self) -> np.ndarray:
        """Free cells of the largest 4-connected region, ``int64 [K, 2]`` ``(x, y)``.

        Random task and robot positions are drawn from these cells so that every
        pair is connected; cells in smaller regions are never sampled.
        """
        labels = self.component_labels
        sizes = np.bincount(labels.ravel())
        sizes[0] = 0
        ys, xs = np.nonzero(labels == int(sizes.argmax()))
        return np.stack([xs, ys], axis=1).astype(np.int64)

    @cached_property
    def compactness(self) -> float:
        """Fraction of cells that are blocked (shelves)."""
        return float(self.obstacles.mean())

    def station_cells(self, kind: str) -> np.ndarray:
        """``int64 [K, 2]`` ``(x, y)`` of the ``"pickup"`` or ``"delivery"`` stations in the
        main connected region (empty when the layout marks none)."""
        mask = getattr(self, kind)
        if mask is None:
            return np.empty((0, 2), dtype=np.int64)
        main = np.zeros_like(mask)
        main[self.main_cells[:, 1], self.main_cells[:, 0]] = True
        ys, xs = np.nonzero(mask & main)
        return np.stack([xs, ys], axis=1).astype(np.int64)

    def describe(self) -> str:
        """One line: size, free cells, compactness, connected regions, stations."""
        sizes = np.bincount(self.component_labels.ravel())[1:]
        regions = (
            "1 connected region"
            if len(sizes) == 1
            else f"{len(sizes)} regions (largest {sizes.max()} cells; tasks and starts use it, "
            f"{int(sizes.sum() - sizes.max())} free cells elsewhere are never used)"
        )
        stations = (
            ", ".join(
                f"{len(self.station_cells(k))} {k}"
                for k in ("pickup", "delivery")
                if getattr(self, k) is not None
            )
            or "no stations"
        )
        return (
            f"{self.name}: {self.width}x{self.height}, {len(self.free_cells)} free cells, "
            f"compactness {self.compactness:.2f}, {regions}, {stations}"
        )

    def in_bounds(self, xy: np.ndarray) -> np.ndarray:
        """Whether each ``(x, y)`` row of ``xy [..., 2]`` lies inside the grid."""
        xy = np.asarray(xy)
        x, y = xy[..., 0], xy[..., 1]
        return (x >= 0) & (x < self.width) & (y >= 0) & (y < self.height)

    def is_free(self, xy: np.ndarray) -> np.ndarray:
        """Whether each ``(x, y)`` row of ``xy [..., 2]`` is inside the grid and free."""
        xy = np.asarray(xy, dtype=np.int64)
        inside = self.in_bounds(xy)
        free = np.zeros(inside.shape, dtype=bool)
        free[inside] = ~self.obstacles[xy[..., 1][inside], xy[..., 0][inside]]
        return free

    def check_cells(self, xy: np.ndarray, what: str) -> None:
        """Raise :class:`LayoutError` naming the first cell of ``xy [K, 2]`` that is not free.

        Args:
            xy: Integer ``(x, y)`` rows.
            what: How to call the cells in the message, e.g. ``"task origin"``.
        """
        xy = np.asarray(xy)
        if xy.size == 0:
            return
        if not np.array_equal(xy, np.round(xy)):
            raise LayoutError(f"{what} coordinates must be integers, got {xy.tolist()}")
        bad = np.flatnonzero(~self.is_free(xy.astype(np.int64)))
        if bad.size:
            i = int(bad[0])
            where = "outside the grid" if not self.in_bounds(xy[i]) else "on an obstacle"
            raise LayoutError(
                f"{what} {i} at (x={int(xy[i, 0])}, y={int(xy[i, 1])}) is {where} of layout "
                f"{self.name!r} ({self.width}x{self.height})"
            )

    def to_ascii(self) -> str:
        """The grid as rows of ``.`` (free) and ``@`` (blocked)."""
        chars = np.where(self.obstacles, "@", ".")
        return "\n".join("".join(row) for row in chars)


def open_grid(width: int, height: int) -> Layout:
    """An obstacle-free ``width x height`` grid (the paper's "Direct" setting)."""
    check_sizes(width=width, height=height)
    return Layout(np.zeros((int(height), int(width)), dtype=bool), name=f"open_{width}x{height}")


def shelf_grid(
    width: int,
    height: int,
    shelf_width: int,
    shelf_height: int,
    aisle: int,
    margin: int,
) -> Layout:
    """A simple warehouse: rows of rectangular shelf blocks separated by aisles.

    Blocks of ``shelf_width x shelf_height`` cells are tiled with ``aisle`` free cells
    between them, leaving a free ``margin`` along every edge, so all free cells are
    connected. Deterministic from its parameters.
    """
    check_sizes(
        width=width,
        height=height,
        shelf_width=shelf_width,
        shelf_height=shelf_height,
        aisle=aisle,
        margin=margin,
    )
    grid = np.zeros((int(height), int(width)), dtype=bool)
    # Centre the block pattern so the margins on opposite edges differ by at most one cell.
    nx = max(0, (width - 2 * margin + aisle) // (shelf_width + aisle))
    ny = max(0, (height - 2 * margin + aisle) // (shelf_height + aisle))
    x_start = (width - (nx * (shelf_width + aisle) - aisle)) // 2
    y_start = (height - (ny * (shelf_height + aisle) - aisle)) // 2
    for j in range(ny):
        y0 = y_start + j * (shelf_height + aisle)
        for i in range(nx):
            x0 = x_start + i * (shelf_width + aisle)
            grid[y0 : y0 + shelf_height, x0 : x0 + shelf_width] = True
    return Layout(grid, name=f"shelves_{width}x{height}")


def check_sizes(minimum: int = 1, **sizes: object) -> None:
    """Check generator parameters: integers (``10.7`` is not silently built as ``10``)
    and at least ``minimum``.

    Raises:
        LayoutError: A size is not an integer or is below ``minimum``; names the key.
    """
    for key, value in sizes.items():
        if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
            raise LayoutError(f"layout.{key} must be an integer, got {value!r}")
        if value < minimum:
            raise LayoutError(f"layout.{key} must be >= {minimum}, got {value}")


def load_layout(path: str | Path) -> Layout:
    """Load a layout file, choosing the parser by extension (:data:`LAYOUT_FORMATS`:
    ``.cfg``, ``.map``, ``.txt``/``.grid`` ASCII).

    Raises:
        LayoutError: The file is missing, its extension names no known format (a
            ``.scen`` or ``.json`` file is not read as an ASCII map), or it is malformed.
    """
    path = Path(path)
    if not path.is_file():
        raise LayoutError(f"layout file not found: {path}")
    suffix = path.suffix.lower()
    if suffix not in LAYOUT_FORMATS:
        known = ", ".join(f"{ext} ({kind})" for ext, kind in LAYOUT_FORMATS.items())
        raise LayoutError(
            f"{path}: unknown layout format {suffix or '(no extension)'!r}; known: {known}"
        )
    try:
        text = path.read_text()
    except (OSError, UnicodeDecodeError) as exc:
        raise LayoutError(f"cannot read layout file {path}: {exc}") from exc
    if suffix == ".cfg":
        grid = _parse_cfg(text, path)
    elif suffix == ".map":
        grid = _parse_movingai(text, path)
    else:
        grid = _parse_rows(text.splitlines(), path, first_line=1)
    return Layout(grid, name=path.stem)


def _parse_cfg(text: str, path: Path) -> np.ndarray:
    lines = text.splitlines()
    header = {}
    for lineno, line in enumerate(lines, start=1):
        if line.strip().startswith("environment:"):
            body_start = lineno
            break
        key, sep, value = line.partition(":")
        if sep:
            header[key.strip()] = value.split()
    else:
        raise LayoutError(f"{path}: no 'environment:' line; not an SBPL .cfg layout")
    try:
        width, height = (int(v) for v in header["discretization(cells)"])
        obsthresh = float(header.get("obsthresh", ["1"])[0])
    except (KeyError, ValueError) as exc:
        raise LayoutError(f"{path}: bad or missing 'discretization(cells): W H' header") from exc
    numbered = [
        (body_start + 1 + i, line.split())
        for i, line in enumerate(lines[body_start:])
        if line.strip()
    ]
    if len(numbered) != height:
        raise LayoutError(f"{path}: header says {height} rows, found {len(numbered)}")
    for i, (lineno, row) in enumerate(numbered):
        if len(row) != width:
            raise LayoutError(
                f"{path}: row {i} (line {lineno}) has {len(row)} cells, expected {width}"
            )
    rows = [row for _, row in numbered]
    try:
        values = np.array(rows, dtype=float)
    except ValueError as exc:
        raise LayoutError(f"{path}: non-numeric cell value ({exc})") from exc
    return values >= obsthresh


def _parse_movingai(text: str, path: Path) -> np.ndarray:
    lines = text.splitlines()
    header: dict[str, str] = {}
    map_line = next((i for i, line in enumerate(lines) if line.strip().lower() == "map"), None)
    if map_line is None:
        raise LayoutError(f"{path}: no 'map' line; not a MovingAI .map file")
    for line in lines[:map_line]:
        key, _, value = line.strip().partition(" ")
        header[key.lower()] = value.strip()
    lineno = map_line + 1
    try:
        height, width = int(header["height"]), int(header["width"])
    except (KeyError, ValueError) as exc:
        raise LayoutError(f"{path}: bad or missing 'height'/'width' header") from exc
    grid = _parse_rows(lines[lineno:], path, first_line=lineno + 1, blocked=_BLOCKED_MAP_CHARS)
    if grid.shape != (height, width):
        raise LayoutError(
            f"{path}: header says {width}x{height}, grid is {grid.shape[1]}x{grid.shape[0]}"
        )
    return grid


def _parse_rows(
    rows: list[str], path: Path, first_line: int, blocked: frozenset[str] = frozenset("@")
) -> np.ndarray:
    # Keep each row's line number in the file, blank lines included, for error messages.
    numbered = [(first_line + i, row.rstrip()) for i, row in enumerate(rows) if row.strip()]
    if not numbered:
        raise LayoutError(f"{path}: empty layout")
    width = len(numbered[0][1])
    for lineno, row in numbered:
        if len(row) != width:
            raise LayoutError(f"{path}: line {lineno} has {len(row)} cells, expected {width}")
    chars = np.array([list(row) for _, row in numbered])
    if blocked == frozenset("@"):
        unknown = {str(c) for c in np.unique(chars)} - {".", "@"}
        if unknown:
            raise LayoutError(
                f"{path}: unknown cell characters {sorted(unknown)}; ASCII layouts use "
                "'.' (free) and '@' (blocked)"
            )
    return np.isin(chars, list(blocked))
