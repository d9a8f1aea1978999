"""Layouts: built-in grids, the three file formats, malformed files and region queries."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import ndimage

from rtaw_marl.errors import LayoutError
from rtaw_marl.sim.layout import Layout, load_layout, open_grid, shelf_grid
from rtaw_marl.sim.options import ShelvesLayoutConfig

pytestmark = pytest.mark.unit

FAST = settings(max_examples=30, deadline=None, database=None)

#: Free-cell counts of the RTAW .cfg layouts, from ../shared/maps/README.md.
RTAW_FREE = {
    "open_64": 3536,
    "usc_64": 3536,
    "tight_64": 3068,
    "tight_2_64": 3068,
    "compact_64": 3296,
    "compact_2_64": 3336,
}

#: A hand-made grid with no symmetry: every blocked cell is at a distinct (x, y).
ASYMMETRIC = "....@\n.@...\n...@.\n"
ASYMMETRIC_BLOCKED_XY = {(4, 0), (1, 1), (3, 2)}


def _write(tmp_path: Path, name: str, text: str) -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def _cfg_text(rows: list[str], width: int, height: int, obsthresh: int = 1) -> str:
    header = [
        f"discretization(cells): {width} {height}",
        f"obsthresh: {obsthresh}",
        "cost_inscribed_thresh: 1",
        "cost_possibly_circumscribed_thresh: 0",
        "cellsize(meters): 1",
        "nominalvel(mpersecs): 1.0",
        "timetoturn45degsinplace(secs): 2.0",
        "start(meters,rads): 0 0 0",
        "end(meters,rads): 1 1 0",
        "environment:",
    ]
    return "\n".join(header + rows) + "\n"


def _blocked_bbox(layout: Layout) -> tuple[int, int, int, int]:
    """Free margins (left, right, top, bottom) around all blocked cells."""
    ys, xs = np.nonzero(layout.obstacles)
    return (
        int(xs.min()),
        layout.width - 1 - int(xs.max()),
        int(ys.min()),
        layout.height - 1 - int(ys.max()),
    )


# ----------------------------------------------------------------- built-in grids


def test_open_grid_shape_and_cells() -> None:
    """open_grid(W, H) is H rows by W columns, all free, with (x, y) free_cells row-major."""
    layout = open_grid(7, 5)
    assert layout.obstacles.shape == (5, 7)
    assert (layout.width, layout.height, layout.scale) == (7, 5, 7.0)
    assert not layout.obstacles.any()
    assert layout.num_components == 1
    cells = layout.free_cells
    assert cells.shape == (35, 2)
    assert cells[:3].tolist() == [[0, 0], [1, 0], [2, 0]]
    assert cells[-1].tolist() == [6, 4]


@pytest.mark.parametrize(("width", "height"), [(0, 5), (5, 0), (-1, 3)])
def test_open_grid_rejects_empty_size(width: int, height: int) -> None:
    """A grid with no cell is a LayoutError naming the size."""
    with pytest.raises(LayoutError, match=r"layout\.(width|height) must be >= 1"):
        open_grid(width, height)


def test_layout_is_immutable_copy() -> None:
    """Layout copies its grid and makes it read-only, so later edits of the input change nothing."""
    grid = np.zeros((3, 4), dtype=bool)
    layout = Layout(grid)
    grid[0, 0] = True
    assert not layout.obstacles[0, 0]
    with pytest.raises(ValueError, match="read-only"):
        layout.obstacles[0, 0] = True


@pytest.mark.parametrize(
    ("grid", "match"),
    [(np.ones((2, 3), dtype=bool), "no free cell"), (np.zeros(4, dtype=bool), "2-D")],
)
def test_layout_rejects_bad_grids(grid: np.ndarray, match: str) -> None:
    """An all-blocked or non-2-D obstacle grid is a LayoutError."""
    with pytest.raises(LayoutError, match=match):
        Layout(grid)


def test_shelf_grid_default_is_connected_and_deterministic() -> None:
    """The default 60x60 shelf grid has shelves, one connected region and is reproducible."""
    a, b = ShelvesLayoutConfig().build(), ShelvesLayoutConfig().build()
    assert a.obstacles.shape == (60, 60)
    assert a.obstacles.any()
    assert a.num_components == 1
    assert np.array_equal(a.obstacles, b.obstacles)
    assert len(a.main_cells) == len(a.free_cells)


@FAST
@given(
    width=st.integers(8, 45),
    height=st.integers(8, 45),
    shelf_width=st.integers(1, 6),
    shelf_height=st.integers(1, 4),
    aisle=st.integers(1, 3),
    margin=st.integers(1, 4),
)
def test_shelf_grid_properties(
    width: int, height: int, shelf_width: int, shelf_height: int, aisle: int, margin: int
) -> None:
    """Every shelf grid is connected, made of shelf-sized blocks, with margins >= margin that
    differ by at most one cell between opposite edges."""
    layout = shelf_grid(width, height, shelf_width, shelf_height, aisle, margin)
    assert layout.obstacles.shape == (height, width)
    assert layout.num_components == 1
    if not layout.obstacles.any():
        # Too small for a single block: nothing to place.
        assert width - 2 * margin < shelf_width or height - 2 * margin < shelf_height
        return
    left, right, top, bottom = _blocked_bbox(layout)
    assert min(left, right, top, bottom) >= margin
    assert abs(left - right) <= 1
    assert abs(top - bottom) <= 1
    labels, count = ndimage.label(layout.obstacles)
    sizes = np.bincount(labels.ravel())[1:]
    assert count >= 1
    assert (sizes == shelf_width * shelf_height).all()
    for sl in ndimage.find_objects(labels):
        assert (sl[0].stop - sl[0].start, sl[1].stop - sl[1].start) == (shelf_height, shelf_width)


@pytest.mark.parametrize(
    "kwargs",
    [{"shelf_width": 0}, {"shelf_height": 0}, {"aisle": 0}, {"margin": 0}],
)
def test_shelf_grid_rejects_bad_parameters(kwargs: dict[str, int]) -> None:
    """Non-positive shelf, aisle or margin sizes are LayoutErrors naming the key."""
    key = next(iter(kwargs))
    with pytest.raises(LayoutError, match=key):
        ShelvesLayoutConfig(**kwargs).build()


# ----------------------------------------------------------------- real data maps


@pytest.mark.parametrize(("stem", "free"), sorted(RTAW_FREE.items()))
def test_load_rtaw_cfg(maps_dir: Path, stem: str, free: int) -> None:
    """Each RTAW .cfg loads as 64x64 with the README's free count, as np.loadtxt(skiprows=10)."""
    path = maps_dir / "rtaw" / f"{stem}.cfg"
    layout = load_layout(path)
    assert layout.name == stem
    assert (layout.width, layout.height) == (64, 64)
    assert int((~layout.obstacles).sum()) == free
    assert len(layout.free_cells) == free
    # RTAW's own loader: rows are y, columns are x, 1 is blocked.
    reference = np.loadtxt(path, skiprows=10) >= 1
    assert np.array_equal(layout.obstacles, reference)


def test_rtaw_layout_pairs_differ(maps_dir: Path) -> None:
    """open/usc, tight/tight_2 and compact/compact_2 are different grids (README notes)."""
    rtaw = maps_dir / "rtaw"
    for a, b, cells in (
        ("open", "usc", 280),
        ("tight", "tight_2", 432),
        ("compact", "compact_2", 360),
    ):
        ga = load_layout(rtaw / f"{a}_64.cfg").obstacles
        gb = load_layout(rtaw / f"{b}_64.cfg").obstacles
        assert int((ga != gb).sum()) == cells


def _movingai_reference(path: Path) -> np.ndarray:
    lines = path.read_text().splitlines()
    body = lines[[line.strip() for line in lines].index("map") + 1 :]
    return np.array([[c in "@T" for c in line] for line in body if line.strip()])


@pytest.mark.parametrize(
    ("relpath", "width", "height", "free"),
    [
        ("movingai/warehouse-10-20-10-2-1.map", 161, 63, 5699),
        ("movingai/warehouse-10-20-10-2-2.map", 170, 84, 9776),
        ("movingai/warehouse-20-40-10-2-1.map", 321, 123, 22599),
        ("movingai/warehouse-20-40-10-2-2.map", 340, 164, 38756),
        ("mapd/warehouse.map", 35, 21, 635),
    ],
)
def test_load_movingai_maps(
    maps_dir: Path, relpath: str, width: int, height: int, free: int
) -> None:
    """MovingAI maps load with the README's size and free count; line index is y, char index x."""
    path = maps_dir / relpath
    layout = load_layout(path)
    assert (layout.width, layout.height) == (width, height)
    assert int((~layout.obstacles).sum()) == free
    assert np.array_equal(layout.obstacles, _movingai_reference(path))


def test_mapd_map_has_no_type_line(maps_dir: Path) -> None:
    """mapd/warehouse.map really lacks the 'type' header line, and still loads."""
    path = maps_dir / "mapd" / "warehouse.map"
    header = path.read_text().splitlines()[:4]
    assert not any(line.startswith("type") for line in header)
    assert load_layout(path).num_components >= 1


# ----------------------------------------------------------------- hand-made files


def test_ascii_axes_convention(tmp_path: Path) -> None:
    """In an ASCII file x is the column and y the row; obstacles are indexed [y, x]."""
    layout = load_layout(_write(tmp_path, "asym.txt", ASYMMETRIC))
    assert (layout.width, layout.height) == (5, 3)
    assert layout.name == "asym"
    ys, xs = np.nonzero(layout.obstacles)
    assert set(zip(xs.tolist(), ys.tolist(), strict=True)) == ASYMMETRIC_BLOCKED_XY
    for x, y in ASYMMETRIC_BLOCKED_XY:
        assert not layout.is_free(np.array([x, y]))
        assert layout.obstacles[y, x]
    # (0, 4) would be the blocked cell if axes were swapped; it is outside the grid.
    assert not layout.in_bounds(np.array([0, 4]))
    assert layout.is_free(np.array([[0, 2], [2, 0], [4, 2]])).all()
    assert layout.to_ascii() == ASYMMETRIC.strip()


def test_cfg_axes_convention_and_obsthresh(tmp_path: Path) -> None:
    """A hand-made .cfg keeps x = column, y = row, and blocks values >= obsthresh only."""
    rows = ["0 0 0 0 2", "0 2 0 1 0", "0 0 0 2 0"]
    layout = load_layout(_write(tmp_path, "asym.cfg", _cfg_text(rows, 5, 3, obsthresh=2)))
    ys, xs = np.nonzero(layout.obstacles)
    assert set(zip(xs.tolist(), ys.tolist(), strict=True)) == ASYMMETRIC_BLOCKED_XY


def test_movingai_axes_and_characters(tmp_path: Path) -> None:
    """A hand-made .map: '@', 'T', 'O', 'W' block; '.', 'G', 'S' are passable."""
    text = "type octile\nheight 3\nwidth 5\nmap\n.G..@\nSTGS.\n...W.\n"
    layout = load_layout(_write(tmp_path, "asym.map", text))
    ys, xs = np.nonzero(layout.obstacles)
    assert set(zip(xs.tolist(), ys.tolist(), strict=True)) == {(4, 0), (1, 1), (3, 2)}
    text_o = "height 1\nwidth 3\nmap\nO.G"
    assert load_layout(_write(tmp_path, "o.map", text_o)).obstacles.tolist() == [
        [True, False, False]
    ]


def test_movingai_legend_is_read_exactly(tmp_path: Path) -> None:
    """Each of MovingAI's seven characters is read as its legend says, one per column."""
    text = "type octile\nheight 1\nwidth 7\nmap\n.GS@OTW\n"
    layout = load_layout(_write(tmp_path, "legend.map", text))
    assert layout.obstacles.tolist() == [[False, False, False, True, True, True, True]]


MOVINGAI_LEGEND = (
    "MovingAI cells are '.', 'G', 'S', LoRR's 'E' (passable) and '@', 'O', 'T', 'W' (blocked)"
)
ASCII_LEGEND = "ASCII layouts use '.' (free) and '@' (blocked)"


@pytest.mark.parametrize(
    ("name", "text", "where"),
    [
        # '#' walls used to read as free: a map of compactness 0.00.
        (
            "hash.map",
            "height 2\nwidth 3\nmap\n.#.\n###\n",
            "line 4, column 2: undefined cell character '#'",
        ),
        (
            "lower.map",
            "height 1\nwidth 3\nmap\n..t\n",
            "line 4, column 3: undefined cell character 't'",
        ),
        (
            "space.map",
            "height 2\nwidth 3\nmap\n...\n. .\n",
            "line 5, column 2: undefined cell character ' '",
        ),
        # A form feed is a character of the row, not a line break that adds a row.
        (
            "ff.map",
            "height 1\nwidth 3\nmap\n.\f.\n",
            "line 4, column 2: undefined cell character '\\x0c'",
        ),
        ("hash.txt", "...\n.#.\n", "line 2, column 2: undefined cell character '#'"),
        ("map.txt", "...\n.T.\n", "line 2, column 2: undefined cell character 'T'"),
        ("digit.txt", "..0\n...\n", "line 1, column 3: undefined cell character '0'"),
    ],
)
def test_undefined_cell_characters(tmp_path: Path, name: str, text: str, where: str) -> None:
    """A character outside the format's legend is one line: file, line, column, the
    character and the valid ones."""
    path = _write(tmp_path, name, text)
    legend = MOVINGAI_LEGEND if name.endswith(".map") else ASCII_LEGEND
    with pytest.raises(LayoutError) as info:
        load_layout(path)
    assert str(info.value) == f"{path}: {where}; {legend}"


THRESH = "line 2: obsthresh must be one finite number, got "
NOT_FINITE = "is not a finite number >= 0"
HEADER = "header lines are 'key: value', each key once; got"
MAP_HEADER = "a MovingAI header is 'type octile', 'height H', 'width W', then 'map'"


@pytest.mark.parametrize(
    ("header", "rows", "message"),
    [
        ("obsthresh: nan", ["0 1", "1 0"], THRESH + "'nan'"),
        ("obsthresh: inf", ["0 1", "1 0"], THRESH + "'inf'"),
        ("obsthresh: 1 2", ["0 1", "1 0"], THRESH + "'1 2'"),
        ("obsthresh: high", ["0 1", "1 0"], THRESH + "'high'"),
        ("obsthresh: 1", ["0 nan", "1 0"], f"line 4, column 2: cell value 'nan' {NOT_FINITE}"),
        ("obsthresh: 1", ["0 1", "inf 0"], f"line 5, column 1: cell value 'inf' {NOT_FINITE}"),
        ("obsthresh: 1", ["0 1", "0 -1"], f"line 5, column 2: cell value '-1' {NOT_FINITE}"),
        ("obsthresh: 1", ["0 1", "0 a"], f"line 5, column 2: cell value 'a' {NOT_FINITE}"),
        ("obsthresh: 1\nobsthresh: 2", ["0 1", "1 0"], f"line 3: {HEADER} 'obsthresh: 2'"),
        ("obsthresh 1", ["0 1", "1 0"], f"line 2: {HEADER} 'obsthresh 1'"),
    ],
)
def test_cfg_refuses_non_finite_values(
    tmp_path: Path, header: str, rows: list[str], message: str
) -> None:
    """A NaN or infinite threshold or cell (which would block nothing), a negative cost, a
    repeated or malformed header line: one error naming the line (and column)."""
    text = "\n".join(["discretization(cells): 2 2", header, "environment:", *rows]) + "\n"
    path = _write(tmp_path, "bad.cfg", text)
    with pytest.raises(LayoutError) as info:
        load_layout(path)
    assert str(info.value) == f"{path}: {message}"


@pytest.mark.parametrize(
    ("name", "text", "message"),
    [
        ("middle.txt", "...\n\n.@.\n", "line 2 is blank inside the grid (a missing row)"),
        ("spaces.txt", "...\n   \n.@.\n", "line 2 is blank inside the grid (a missing row)"),
        (
            "middle.map",
            "height 3\nwidth 3\nmap\n...\n\n.@.",
            "line 5 is blank inside the grid (a missing row)",
        ),
        ("short.map", "height 3\nwidth 3\nmap\n...\n.@.\n", "header says 3 rows (height), found 2"),
        ("long.map", "height 1\nwidth 3\nmap\n...\n.@.\n", "header says 1 rows (height), found 2"),
        ("wide.map", "height 2\nwidth 2\nmap\n...\n.@.\n", "line 4 has 3 cells, expected 2"),
        ("nomap.map", "height 1\nwidth 3\n...\n", "no 'map' line; not a MovingAI .map file"),
        (
            "nowidth.map",
            "height 1\nmap\n...",
            "header 'width' must be a positive integer, got '(none)'",
        ),
        (
            "zero.map",
            "height 0\nwidth 3\nmap\n",
            "header 'height' must be a positive integer, got '0'",
        ),
        (
            "sign.map",
            "height +1\nwidth 3\nmap\n.",
            "header 'height' must be a positive integer, got '+1'",
        ),
        (
            "extra.map",
            "height 1\ncolors 2\nmap\n.",
            f"line 2: unknown or repeated header field 'colors'; {MAP_HEADER}",
        ),
        (
            "twice.map",
            "height 1\nheight 2\nmap\n.",
            f"line 2: unknown or repeated header field 'height'; {MAP_HEADER}",
        ),
        ("type.map", "type hex\nheight 1\nwidth 3\nmap\n...\n", "map type 'hex' is not 'octile'"),
    ],
)
def test_grid_shape_misreads_are_refused(
    tmp_path: Path, name: str, text: str, message: str
) -> None:
    """A blank row inside the grid (once dropped silently) and a header that disagrees
    with the grid are one error naming the file and the line."""
    path = _write(tmp_path, name, text)
    with pytest.raises(LayoutError) as info:
        load_layout(path)
    assert str(info.value) == f"{path}: {message}"


def test_blank_lines_around_the_grid_are_fine(tmp_path: Path) -> None:
    """Blank lines before and after the grid (a trailing newline or two) are not rows."""
    for name, text in (
        ("around.txt", "\n\n" + ASYMMETRIC + "\n\n   \n"),
        ("around.map", "height 3\nwidth 5\nmap\n" + ASYMMETRIC + "\n\n"),
    ):
        layout = load_layout(_write(tmp_path, name, text))
        assert layout.to_ascii() == ASYMMETRIC.strip()


@pytest.mark.parametrize("name", ["asym.txt", "asym.map", "asym.cfg"])
def test_bom_and_crlf_are_read_as_written(tmp_path: Path, name: str) -> None:
    """A UTF-8 byte-order mark and CRLF line ends give the same grid as the plain file."""
    if name.endswith(".txt"):
        text = ASYMMETRIC
    elif name.endswith(".map"):
        text = "type octile\nheight 3\nwidth 5\nmap\n" + ASYMMETRIC
    else:
        text = _cfg_text(["0 0 0 0 1", "0 1 0 0 0", "0 0 0 1 0"], 5, 3)
    plain = load_layout(_write(tmp_path, name, text))
    assert {
        tuple(c) for c in np.argwhere(plain.obstacles)[:, ::-1].tolist()
    } == ASYMMETRIC_BLOCKED_XY
    dos = tmp_path / "dos" / name
    dos.parent.mkdir()
    dos.write_bytes(b"\xef\xbb\xbf" + text.replace("\n", "\r\n").encode())
    assert np.array_equal(load_layout(dos).obstacles, plain.obstacles)


@pytest.mark.parametrize(
    ("name", "text", "match"),
    [
        ("ragged.txt", "...\n..\n...\n", r"line 2 has 2 cells, expected 3"),
        ("empty.txt", "\n\n", "empty layout"),
        ("blocked.txt", "@@\n@@\n", "no free cell"),
        ("noenv.cfg", "discretization(cells): 2 1\nobsthresh: 1\n0 0\n", "environment:"),
        ("nodisc.cfg", "obsthresh: 1\nenvironment:\n0 0\n", "discretization"),
        ("baddisc.cfg", "discretization(cells): 2\nenvironment:\n0 0\n", "discretization"),
        (
            "rows.cfg",
            "discretization(cells): 2 3\nenvironment:\n0 0\n0 0\n",
            "header says 3 rows, found 2",
        ),
        (
            "width.cfg",
            "discretization(cells): 2 2\nenvironment:\n0 0\n0 0 0\n",
            r"row 1 \(line 4\) has 3 cells, expected 2",
        ),
        ("nonnum.cfg", "discretization(cells): 2 1\nenvironment:\n0 a\n", "cell value 'a'"),
        ("nomap.map", "type octile\nheight 1\nwidth 2\n..\n", "no 'map' line"),
        ("noheight.map", "type octile\nwidth 2\nmap\n..\n", "'height' must be a positive"),
        ("badheight.map", "height x\nwidth 2\nmap\n..\n", "'height' must be a positive"),
        ("dims.map", "height 2\nwidth 2\nmap\n..\n", r"header says 2 rows \(height\), found 1"),
        ("ragged.map", "height 2\nwidth 3\nmap\n...\n..\n", r"line 5 has 2 cells, expected 3"),
    ],
)
def test_malformed_files(tmp_path: Path, name: str, text: str, match: str) -> None:
    """Each kind of malformed layout file is a LayoutError whose message names the problem
    and the file."""
    path = _write(tmp_path, name, text)
    with pytest.raises(LayoutError, match=match) as info:
        load_layout(path)
    if "no free cell" not in match:
        assert name in str(info.value)


def test_missing_file(tmp_path: Path) -> None:
    """A missing file is a LayoutError naming the path."""
    with pytest.raises(LayoutError, match=r"not found: .*nope\.map"):
        load_layout(tmp_path / "nope.map")


def test_ascii_error_line_number_counts_blank_lines(tmp_path: Path) -> None:
    """The reported line of a ragged row is its real line in the file (blank lines included)."""
    path = _write(tmp_path, "blank.txt", "\n...\n..\n")
    with pytest.raises(LayoutError, match="line 3 has 2 cells"):
        load_layout(path)


# ----------------------------------------------------------------- queries


def test_check_cells() -> None:
    """check_cells accepts free cells and names the first bad one (outside, obstacle, fraction)."""
    layout = Layout(np.array([[False, True, False], [False, False, False]]), name="tiny")
    layout.check_cells(np.array([[0, 0], [2, 1]]), "robot")
    layout.check_cells(np.empty((0, 2)), "robot")
    with pytest.raises(LayoutError, match=r"robot 1 at \(x=1, y=0\) is on an obstacle.*'tiny'"):
        layout.check_cells(np.array([[0, 0], [1, 0], [5, 5]]), "robot")
    with pytest.raises(LayoutError, match=r"task 0 at \(x=3, y=0\) is outside the grid.*3x2"):
        layout.check_cells(np.array([[3, 0]]), "task")
    with pytest.raises(LayoutError, match=r"task 0 at \(x=0, y=-1\) is outside"):
        layout.check_cells(np.array([[0, -1]]), "task")
    with pytest.raises(LayoutError, match="must be integers"):
        layout.check_cells(np.array([[0.5, 0.0]]), "task")


def test_components_and_main_cells() -> None:
    """A wall splits the grid into two 4-connected regions; main_cells is the larger one."""
    text = "..@...\n..@...\n..@...\n"
    grid = np.array([[c == "@" for c in row] for row in text.split()])
    layout = Layout(grid)
    assert layout.num_components == 2
    labels = layout.component_labels
    assert (labels[grid] == 0).all()
    assert labels[0, 0] != labels[0, 3]
    assert len(np.unique(labels[:, :2])) == 1
    main = {tuple(c) for c in layout.main_cells.tolist()}
    assert main == {(x, y) for x in range(3, 6) for y in range(3)}
    assert len(layout.free_cells) == 15


def test_diagonal_cells_are_not_connected() -> None:
    """Connectivity is 4-neighbour: free cells touching only diagonally are separate regions."""
    layout = Layout(np.array([[False, True], [True, False]]))
    assert layout.num_components == 2
    assert len(layout.main_cells) == 1


def test_lorr_warehouse_map_loads_as_lorr_reads_it(maps_dir: Path) -> None:
    """LoRR's maps use an ``E`` (emitter) cell; LoRR blocks ``@`` and ``T`` only."""
    path = maps_dir / "lorr" / "maps" / "warehouse_large.map"
    rows = path.read_text().splitlines()[4:]
    blocked = np.array([[c in "@T" for c in row] for row in rows])
    assert "E" in "".join(rows)
    layout = load_layout(path)
    assert (layout.width, layout.height) == (500, 140)
    assert np.array_equal(layout.obstacles, blocked)
