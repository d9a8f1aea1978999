"""Warehouse layouts: a boolean obstacle grid and its loaders.

Coordinates everywhere in rtaw_marl are ``(x, y)`` with ``x`` the column and ``y``
the row, both starting at 0 in the top-left corner of the file as written. Arrays
indexed by cell are indexed ``[y, x]``.

Supported files (UTF-8, a byte-order mark and CRLF line ends are read as such):

* SBPL-style ``.cfg`` (the original RTAW code's layouts): ``key: value`` header lines
  up to ``environment:``, then ``H`` rows of ``W`` space-separated numbers, ``0`` free
  and ``>= obsthresh`` blocked; a NaN, infinite or negative value (or threshold) is an
  error, not a free cell. Blank lines between rows are skipped, as SBPL does.
* MovingAI ``.map`` (octile): ``type octile`` (optional), ``height H``, ``width W``,
  ``map``, then exactly ``H`` lines of ``W`` characters of MovingAI's legend: ``.``,
  ``G``, ``S`` passable, ``@``, ``O``, ``T``, ``W`` blocked; and LoRR's ``E``
  (emitter, passable), so the League of Robot Runners' maps load as LoRR reads them.
* ASCII ``.txt``/``.grid``: rows of ``.`` (free) and ``@`` (blocked), no header.

In ``.map`` and ASCII files any other character, a ragged row, a blank line inside the
grid (blank lines before and after it are fine) or a header that disagrees with the
grid is a :class:`LayoutError` naming the file and line (and column). Any other
extension is an error naming the formats (:data:`LAYOUT_FORMATS`), rather than a
MovingAI ``.scen`` or a JSON file misread as an ASCII map.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path

import numpy as np
from scipy import ndimage

from rtaw_marl.errors import LayoutError
from rtaw_marl.sim.maps import resolve_path

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


#: MovingAI's legend (movingai.com/benchmarks/formats.html): the passable characters,
#: the blocked ones (``W``, water, blocks ground robots) and how a message lists them.
#: Any other character is an error, not a free cell. ``E`` is LoRR's emitter cell, an
#: extension its maps use (LoRR blocks ``@`` and ``T`` only, so it is passable).
_MOVINGAI_LEGEND = (
    ".GSE", "@OTW",
    "MovingAI cells are '.', 'G', 'S', LoRR's 'E' (passable) and '@', 'O', 'T', 'W' (blocked)",
)  # fmt: skip
_ASCII_LEGEND = (".", "@", "ASCII layouts use '.' (free) and '@' (blocked)")
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

    Args:
        path: The file, or ``builtin:NAME`` for a shipped map (:mod:`rtaw_marl.sim.maps`).

    Raises:
        ConfigError: ``builtin:`` names no shipped map (the message lists them).
        LayoutError: The file is missing, its extension names no known format (a
            ``.scen`` or ``.json`` file is not read as an ASCII map), or it is malformed
            (the message names the line, and the column of a bad cell).
    """
    path = resolve_path(path)
    if not path.is_file():
        raise LayoutError(f"layout file not found: {path}")
    suffix = path.suffix.lower()
    if suffix not in LAYOUT_FORMATS:
        known = ", ".join(f"{ext} ({kind})" for ext, kind in LAYOUT_FORMATS.items())
        raise LayoutError(
            f"{path}: unknown layout format {suffix or '(no extension)'!r}; known: {known}"
        )
    try:
        text = path.read_text(encoding="utf-8-sig")
    except (OSError, UnicodeDecodeError) as exc:
        raise LayoutError(f"cannot read layout file {path}: {exc}") from exc
    # read_text turns CRLF (and CR) into "\n"; split there only: str.splitlines would
    # also split a row at a form feed or a vertical tab, silently adding a row.
    lines = text.split("\n")
    if suffix == ".cfg":
        grid = _parse_cfg(lines, path)
    elif suffix == ".map":
        grid = _parse_movingai(lines, path)
    else:
        grid = _cells(_grid_rows(lines, 1, path), path, _ASCII_LEGEND)
    return Layout(grid, name=path.stem)


def _parse_cfg(lines: list[str], path: Path) -> np.ndarray:
    body = next((i for i, line in enumerate(lines) if line.strip().startswith("environment:")), -1)
    if body < 0:
        raise LayoutError(f"{path}: no 'environment:' line; not an SBPL .cfg layout")
    header: dict[str, tuple[int, list[str]]] = {}
    for lineno, line in enumerate(lines[:body], start=1):
        key, sep, value = (part.strip() for part in line.partition(":"))
        if (key or sep) and (not sep or key in header):
            raise LayoutError(
                f"{path}: line {lineno}: header lines are 'key: value', each key once; "
                f"got {line.strip()[:40]!r}"
            )
        header[key] = (lineno, value.split())
    try:
        width, height = (int(v) for v in header["discretization(cells)"][1])
    except (KeyError, ValueError) as exc:
        raise LayoutError(f"{path}: bad or missing 'discretization(cells): W H' header") from exc
    if min(width, height) < 1:
        raise LayoutError(f"{path}: 'discretization(cells): {width} {height}' has no cell")
    lineno, values = header.get("obsthresh", (0, ["1"]))
    # A NaN threshold would block nothing: every comparison with it is False.
    obsthresh = float(values[0]) if len(values) == 1 and _is_number(values[0]) else np.nan
    if not np.isfinite(obsthresh):
        raise LayoutError(
            f"{path}: line {lineno}: obsthresh must be one finite number, got {' '.join(values)!r}"
        )
    # SBPL and np.loadtxt both skip blank lines between rows; the header's H counts rows.
    numbered = [(body + 2 + i, line.split()) for i, line in enumerate(lines[body + 1 :])]
    numbered = [(lineno, row) for lineno, row in numbered if row]
    if len(numbered) != height:
        raise LayoutError(f"{path}: header says {height} rows, found {len(numbered)}")
    for i, (lineno, row) in enumerate(numbered):
        if len(row) != width:
            raise LayoutError(
                f"{path}: row {i} (line {lineno}) has {len(row)} cells, expected {width}"
            )
    return _cfg_values(numbered, path) >= obsthresh


def _cfg_values(numbered: list[tuple[int, list[str]]], path: Path) -> np.ndarray:
    """The cell values ``float [H, W]``: finite numbers ``>= 0`` (SBPL stores costs as
    unsigned bytes, so a negative cost there is a large one, not a free cell)."""
    rows = [row for _, row in numbered]
    try:
        values = np.array(rows, dtype=float)
    except ValueError:  # a token is not a number: a NaN marks it for the message below
        values = np.array([[float(v) if _is_number(v) else np.nan for v in row] for row in rows])
    bad = np.argwhere(~np.isfinite(values) | (values < 0))
    if len(bad):
        i, j = (int(k) for k in bad[0])
        raise LayoutError(
            f"{path}: line {numbered[i][0]}, column {j + 1}: cell value {rows[i][j]!r} is "
            "not a finite number >= 0"
        )
    return values


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _parse_movingai(lines: list[str], path: Path) -> np.ndarray:
    body = next((i for i, line in enumerate(lines) if line.strip().lower() == "map"), -1)
    if body < 0:
        raise LayoutError(f"{path}: no 'map' line; not a MovingAI .map file")
    header: dict[str, str] = {}
    for lineno, line in enumerate(lines[:body], start=1):
        key, _, value = line.strip().partition(" ")
        if key and (key.lower() not in ("type", "height", "width") or key.lower() in header):
            raise LayoutError(
                f"{path}: line {lineno}: unknown or repeated header field {key!r}; a MovingAI "
                "header is 'type octile', 'height H', 'width W', then 'map'"
            )
        header[key.lower()] = value.strip()
    if header.get("type", "octile") != "octile":
        raise LayoutError(f"{path}: map type {header['type']!r} is not 'octile'")
    size = {key: header.get(key, "(none)") for key in ("height", "width")}
    for key, value in size.items():
        if not (value.isascii() and value.isdigit() and int(value) >= 1):
            raise LayoutError(f"{path}: header '{key}' must be a positive integer, got {value!r}")
    rows = _grid_rows(lines[body + 1 :], body + 2, path)
    if len(rows) != int(size["height"]):
        raise LayoutError(f"{path}: header says {size['height']} rows (height), found {len(rows)}")
    return _cells(rows, path, _MOVINGAI_LEGEND, int(size["width"]))


def _grid_rows(lines: list[str], first_line: int, path: Path) -> list[tuple[int, str]]:
    """The grid's rows with their line numbers in the file. Blank lines before and after
    the grid are skipped; one inside it is an error (dropping it would shift every row
    below it by one)."""
    rows = [(first_line + i, line.rstrip(" \t")) for i, line in enumerate(lines)]
    filled = [i for i, (_, row) in enumerate(rows) if row]
    if not filled:
        raise LayoutError(f"{path}: empty layout")
    rows = rows[filled[0] : filled[-1] + 1]
    blank = next((lineno for lineno, row in rows if not row), None)
    if blank is not None:
        raise LayoutError(f"{path}: line {blank} is blank inside the grid (a missing row)")
    return rows


def _cells(
    rows: list[tuple[int, str]], path: Path, legend: tuple[str, str, str], width: int | None = None
) -> np.ndarray:
    """The obstacle grid of ``rows``, each ``width`` characters (default: the first
    row's) of ``legend``; the first ragged row or undefined character is an error."""
    width = len(rows[0][1]) if width is None else width
    free, blocked_chars, listing = legend
    allowed = frozenset(free + blocked_chars)
    for lineno, row in rows:
        if len(row) != width:
            raise LayoutError(f"{path}: line {lineno} has {len(row)} cells, expected {width}")
        if not allowed.issuperset(row):
            col = next(j for j, char in enumerate(row) if char not in allowed)
            raise LayoutError(
                f"{path}: line {lineno}, column {col + 1}: undefined cell character "
                f"{row[col]!r}; {listing}"
            )
    codes = np.frombuffer("".join(row for _, row in rows).encode("ascii"), dtype=np.uint8)
    blocked = np.zeros(128, dtype=bool)
    blocked[[ord(char) for char in blocked_chars]] = True
    return blocked[codes].reshape(len(rows), width)
