"""Navigators: Euclidean and 4-connected shortest-path distances, slots, paths and errors."""

from __future__ import annotations

from collections import deque

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from rtaw_marl.errors import ConfigError, LayoutError
from rtaw_marl.sim.distances import (
    DistanceModel,
    EuclideanDistance,
    GridDistance,
    TargetSlots,
)
from rtaw_marl.sim.layout import Layout, open_grid
from rtaw_marl.sim.options import ShelvesLayoutConfig, navigator_option

pytestmark = pytest.mark.unit

FAST = settings(max_examples=30, deadline=None, database=None)

#: Two regions split by a full wall at x = 2.
TWO_REGIONS = np.array([[c == "@" for c in row] for row in ("..@...", "..@...", "..@...")])


def bfs(grid: np.ndarray, source: tuple[int, int]) -> dict[tuple[int, int], int]:
    """Plain 4-connected BFS from ``source`` (x, y) over free cells; reachable cell -> steps."""
    height, width = grid.shape
    dist = {source: 0}
    queue = deque([source])
    while queue:
        x, y = queue.popleft()
        for nx, ny in ((x + 1, y), (x - 1, y), (x, y + 1), (x, y - 1)):
            if 0 <= nx < width and 0 <= ny < height and not grid[ny, nx] and (nx, ny) not in dist:
                dist[(nx, ny)] = dist[(x, y)] + 1
                queue.append((nx, ny))
    return dist


@st.composite
def small_layouts(draw: st.DrawFn) -> Layout:
    """Random grids up to 7x7 with at least one free cell."""
    height = draw(st.integers(1, 7))
    width = draw(st.integers(1, 7))
    grid = draw(arrays(np.bool_, (height, width), elements=st.booleans()))
    if grid.all():
        grid[draw(st.integers(0, height - 1)), draw(st.integers(0, width - 1))] = False
    return Layout(grid)


def _assert_valid_path(layout: Layout, path: np.ndarray, a: tuple[int, int], b: tuple[int, int]):
    assert path.ndim == 2
    assert path.shape[1] == 2
    assert tuple(path[0]) == a
    assert tuple(path[-1]) == b
    assert layout.is_free(path).all()
    steps = np.abs(np.diff(path, axis=0)).sum(axis=1)
    assert (steps == 1).all()


# ----------------------------------------------------------------- direct


@FAST
@given(arrays(np.int64, (6, 4), elements=st.integers(-50, 50)))
def test_direct_distance_is_hypot(xy: np.ndarray) -> None:
    """Direct distances (row-wise and matrix) are the Euclidean hypot, obstacles ignored."""
    nav = EuclideanDistance(ShelvesLayoutConfig(width=20, height=20).build())
    a, b = xy[:, :2], xy[:, 2:]
    expected = [np.hypot(*(p - q)) for p, q in zip(a, b, strict=True)]
    np.testing.assert_allclose(nav.distance(a, b), expected, rtol=1e-12)
    matrix = nav.distance_matrix(a, b)
    assert matrix.shape == (6, 6)
    for i in range(6):
        for j in range(6):
            assert matrix[i, j] == pytest.approx(np.hypot(*(a[i] - b[j])), rel=1e-12)


def test_direct_path_and_connectivity() -> None:
    """A direct path is the straight segment's two ends; split regions are never an error."""
    nav = EuclideanDistance(Layout(TWO_REGIONS))
    assert nav.path((0, 0), (5, 2)).tolist() == [[0, 0], [5, 2]]
    nav.check_connected(np.array([[0, 0], [5, 2]]), "cell")
    assert nav.distance(np.array([[0, 0]]), np.array([[5, 2]]))[0] == pytest.approx(np.hypot(5, 2))


# ----------------------------------------------------------------- astar vs BFS


@FAST
@given(small_layouts())
def test_astar_matches_plain_bfs(layout: Layout) -> None:
    """A* distances equal a plain BFS on random grids, are symmetric, and its paths are valid
    4-connected free-cell paths with distance + 1 cells; unreachable pairs raise LayoutError."""
    nav = GridDistance(layout)
    cells = [tuple(c) for c in layout.free_cells.tolist()]
    fields = {c: bfs(layout.obstacles, c) for c in cells}
    reach_a, reach_b, expected, unreachable = [], [], [], []
    for a in cells:
        for b in cells:
            if b in fields[a]:
                reach_a.append(a)
                reach_b.append(b)
                expected.append(fields[a][b])
            else:
                unreachable.append((a, b))
    got = nav.distance(np.array(reach_a), np.array(reach_b))
    np.testing.assert_array_equal(got, expected)
    back = nav.distance(np.array(reach_b), np.array(reach_a))
    np.testing.assert_array_equal(back, got)
    for k in range(0, len(reach_a), max(1, len(reach_a) // 25)):
        a, b = reach_a[k], reach_b[k]
        path = nav.path(a, b)
        _assert_valid_path(layout, path, a, b)
        assert len(path) == expected[k] + 1
    if unreachable:
        a, b = unreachable[0]
        with pytest.raises(LayoutError, match="no path"):
            nav.distance(np.array([a]), np.array([b]))
        with pytest.raises(LayoutError):
            nav.path(a, b)
        with pytest.raises(LayoutError, match="different connected regions"):
            nav.check_connected(np.array([a, b]), "cell")
    else:
        nav.check_connected(np.array(cells), "cell")


@FAST
@given(small_layouts())
def test_astar_distance_matrix_matches_distance(layout: Layout) -> None:
    """distance_matrix over the main region equals pairwise distance() and the BFS."""
    nav = GridDistance(layout)
    cells = layout.main_cells
    matrix = nav.distance_matrix(cells, cells)
    assert matrix.shape == (len(cells), len(cells))
    ii, jj = np.meshgrid(np.arange(len(cells)), np.arange(len(cells)), indexing="ij")
    pairwise = nav.distance(cells[ii.ravel()], cells[jj.ravel()]).reshape(matrix.shape)
    np.testing.assert_array_equal(matrix, pairwise)
    for i, c in enumerate(cells.tolist()):
        field = bfs(layout.obstacles, tuple(c))
        assert [field[tuple(d)] for d in cells.tolist()] == matrix[i].tolist()


def test_astar_open_grid_is_manhattan() -> None:
    """On an obstacle-free grid the 4-connected distance is the Manhattan distance."""
    layout = open_grid(9, 6)
    nav = GridDistance(layout)
    cells = layout.free_cells
    expected = np.abs(cells[:, None, :] - cells[None, :, :]).sum(axis=2)
    np.testing.assert_array_equal(nav.distance_matrix(cells, cells), expected)


def test_astar_detours_around_shelves() -> None:
    """A* goes around a wall that Direct ignores: the detour is longer than the straight line."""
    grid = np.zeros((5, 5), dtype=bool)
    grid[0:4, 2] = True  # wall at x=2 with a gap only at the bottom row
    layout = Layout(grid)
    a, b = np.array([[0, 0]]), np.array([[4, 0]])
    assert GridDistance(layout).distance(a, b)[0] == 4 + 2 * 4
    assert EuclideanDistance(layout).distance(a, b)[0] == 4
    path = GridDistance(layout).path((0, 0), (4, 0))
    _assert_valid_path(layout, path, (0, 0), (4, 0))
    assert [2, 4] in path.tolist()


# ----------------------------------------------------------------- slots


@pytest.mark.parametrize("nav_name", ["direct", "astar"])
def test_target_slots_match_distance_matrix(nav_name: str) -> None:
    """TargetSlots (set, distances_from, distances_from_one, distance_to) agree with
    distance_matrix, including after a slot is re-targeted."""
    layout = ShelvesLayoutConfig(
        width=24, height=18, shelf_width=4, shelf_height=2, aisle=2, margin=2
    ).build()
    nav: DistanceModel = navigator_option(nav_name).distance_model(layout)
    rng = np.random.default_rng(7)
    cells = layout.main_cells
    targets = cells[rng.choice(len(cells), size=4, replace=False)]
    slots: TargetSlots = nav.target_slots(4)
    assert slots.size == 4
    for i, (x, y) in enumerate(targets.tolist()):
        slots.set(i, x, y)
    sources = cells[rng.choice(len(cells), size=40, replace=False)]

    def check() -> None:
        expected = nav.distance_matrix(sources, targets)
        np.testing.assert_allclose(slots.distances_from(sources), expected, rtol=1e-12)
        for p, (x, y) in enumerate(sources.tolist()):
            np.testing.assert_allclose(slots.distances_from_one(x, y), expected[p], rtol=1e-12)
            for s in range(4):
                assert slots.distance_to(s, x, y) == pytest.approx(expected[p, s], rel=1e-12)

    check()
    new = cells[rng.integers(len(cells))]
    while any((new == t).all() for t in targets):
        new = cells[rng.integers(len(cells))]
    targets[2] = new
    slots.set(2, int(new[0]), int(new[1]))
    check()


def test_field_slots_unreachable_raise() -> None:
    """An A* slot whose target lies in another region raises LayoutError from distance_to."""
    layout = Layout(TWO_REGIONS)
    slots = GridDistance(layout).target_slots(1)
    slots.set(0, 5, 1)
    assert slots.distance_to(0, 3, 0) == 3.0
    with pytest.raises(LayoutError, match="no path"):
        slots.distance_to(0, 0, 0)


# ----------------------------------------------------------------- errors


def test_unreachable_pairs_raise() -> None:
    """On a two-region grid, A* distance, distance_matrix and check_connected raise LayoutError."""
    layout = Layout(TWO_REGIONS, name="split")
    nav = GridDistance(layout)
    left, right = np.array([[0, 1]]), np.array([[4, 2]])
    with pytest.raises(LayoutError, match=r"no path from \(x=0, y=1\) to \(x=4, y=2\).*'split'"):
        nav.distance(left, right)
    with pytest.raises(LayoutError, match="no path"):
        nav.distance_matrix(np.array([[3, 0], [0, 1]]), np.array([[4, 2]]))
    with pytest.raises(LayoutError, match=r"cell 2 at \(x=1, y=0\).*different connected regions"):
        nav.check_connected(np.array([[3, 0], [5, 2], [1, 0]]), "cell")
    nav.check_connected(np.array([[3, 0], [5, 2]]), "cell")
    assert nav.distance(np.array([[3, 0]]), np.array([[5, 2]]))[0] == 4.0


def test_navigator_option_builds_its_distance_model() -> None:
    """A navigator option's distance_model builds the named class; an unknown name lists the
    registered ones."""
    layout = open_grid(4, 4)
    assert isinstance(navigator_option("astar").distance_model(layout), GridDistance)
    assert isinstance(navigator_option("direct").distance_model(layout), EuclideanDistance)
    assert navigator_option("direct").distance_model(layout).layout is layout
    with pytest.raises(
        ConfigError, match=r"unknown navigator 'dijkstra'.*astar, cbs, direct, pibt, sipp"
    ):
        navigator_option("dijkstra").distance_model(layout)


# ----------------------------------------------------------------- cache


def test_lru_eviction_keeps_answers_right() -> None:
    """With a tiny field cache (64 fields) fields are evicted and recomputed, and distances
    (batched, matrix, path, slots) stay equal to the BFS."""
    layout = ShelvesLayoutConfig(
        width=16, height=14, shelf_width=3, shelf_height=2, aisle=1, margin=1
    ).build()
    nav = GridDistance(layout, cache_mb=1e-9)
    cells = layout.main_cells
    assert len(cells) > 100
    fields = [bfs(layout.obstacles, tuple(c)) for c in cells.tolist()]
    reference = np.array([[f[tuple(d)] for d in cells.tolist()] for f in fields])
    np.testing.assert_array_equal(nav.distance_matrix(cells, cells), reference)
    first = nav.fields_computed
    assert first == len(cells)
    # Every target again: most fields were evicted, so they are computed a second time.
    ii, jj = np.meshgrid(np.arange(len(cells)), np.arange(len(cells)), indexing="ij")
    got = nav.distance(cells[ii.ravel()], cells[jj.ravel()]).reshape(reference.shape)
    np.testing.assert_array_equal(got, reference)
    assert nav.fields_computed >= first + len(cells) - 64
    slots = nav.target_slots(3)
    for s, k in enumerate((0, 50, 100)):
        slots.set(s, *cells[k].tolist())
    np.testing.assert_array_equal(slots.distances_from(cells), reference[:, [0, 50, 100]])
    for k in range(0, len(cells), 17):
        path = nav.path(tuple(cells[k]), tuple(cells[-1 - k]))
        assert len(path) == reference[k, -1 - k] + 1


def test_cell_slots_match_dense_field_slots(monkeypatch: pytest.MonkeyPatch) -> None:
    """Large pools keep cells, not fields (beyond SLOT_FIELDS_BYTES); every query gives
    the dense copy's distances, from few sources or from many."""
    from rtaw_marl.sim import distances as dist

    rng = np.random.default_rng(5)
    layout = Layout(rng.random((20, 30)) < 0.15)
    cells = layout.main_cells
    nav = GridDistance(layout)
    dense = dist._FieldSlots(nav, 40)
    sparse = dist._CellSlots(nav, 40)
    for slot, (x, y) in enumerate(cells[rng.choice(len(cells), 40)].tolist()):
        dense.set(slot, x, y)
        sparse.set(slot, x, y)
    few, many = cells[:3], cells[rng.choice(len(cells), 100)]
    sub = np.array([4, 0, 17])
    np.testing.assert_array_equal(sparse.distances_from(few), dense.distances_from(few))
    np.testing.assert_array_equal(sparse.distances_from(many), dense.distances_from(many))
    np.testing.assert_array_equal(sparse.distances_from(many, sub), dense.distances_from(many, sub))
    x, y = cells[7]
    np.testing.assert_array_equal(sparse.distances_from_one(x, y), dense.distances_from_one(x, y))
    assert sparse.distance_to(3, x, y) == dense.distance_to(3, x, y)
    assert isinstance(nav.target_slots(40), dist._FieldSlots)
    monkeypatch.setattr(dist, "SLOT_FIELDS_BYTES", 40 * 32 * 22 * 4 - 1)
    assert isinstance(nav.target_slots(40), dist._CellSlots)
