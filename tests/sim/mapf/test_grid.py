"""The planners' Grid: one cell encoding, neighbours, distance fields, paths, flood fills."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from rtaw_marl.errors import LayoutError
from rtaw_marl.sim.distances import GridDistance
from rtaw_marl.sim.layout import Layout
from rtaw_marl.sim.mapf import Grid
from rtaw_marl.sim.options import ShelvesLayoutConfig

pytestmark = pytest.mark.unit

ROWS = ("..@..", ".@@..", ".....")


def ascii_grid(*rows: str) -> Grid:
    return Grid(np.array([[c == "." for c in row] for row in rows]))


def test_cells_round_trip() -> None:
    """cell(x, y) = y * width + x; xy and the vectorised forms invert it, for every cell."""
    grid = ascii_grid(*ROWS)
    assert (grid.width, grid.height, grid.size) == (5, 3, 15)
    xy = np.array([(x, y) for y in range(3) for x in range(5)])
    cells = grid.cells(xy)
    np.testing.assert_array_equal(cells, np.arange(15))
    np.testing.assert_array_equal(grid.xys(cells), xy)
    for c in range(grid.size):
        assert grid.cell(*grid.xy(c)) == c
    assert grid.cell(3, 2) == 13
    assert grid.xy(13) == (3, 2)
    assert grid.xys(np.array([[13, 0]])).shape == (1, 2, 2)
    assert not grid.is_free(grid.cell(2, 0))
    assert grid.free.shape == (3, 5)
    with pytest.raises(ValueError, match="read-only"):
        grid.free[0, 0] = False


def test_neighbours_are_free_and_ordered_right_left_down_up() -> None:
    grid = ascii_grid(*ROWS)
    assert grid.neighbours(grid.cell(0, 1)) == [grid.cell(0, 2), grid.cell(0, 0)]
    assert grid.neighbours(grid.cell(3, 1)) == [
        grid.cell(4, 1), grid.cell(3, 2), grid.cell(3, 0)
    ]  # fmt: skip
    # No wrap-around at the row ends.
    assert grid.cell(0, 1) not in grid.neighbours(grid.cell(4, 0))


def test_fields_match_the_astar_distance_model() -> None:
    layout = ShelvesLayoutConfig(width=20, height=14).build()
    grid, nav = Grid.from_layout(layout), GridDistance(layout)
    cells = layout.free_cells[::7]
    for x, y in cells[:10].tolist():
        expected = nav.field(x, y).reshape(layout.height + 2, layout.width + 2)[1:-1, 1:-1]
        np.testing.assert_array_equal(grid.field(grid.cell(x, y)).reshape(14, 20), expected)
    a, b = grid.cell(*cells[0]), grid.cell(*cells[-1])
    assert grid.distance(a, b) == nav.distance(cells[:1], cells[-1:])[0]
    path = grid.path(a, b)
    assert len(path) == grid.distance(a, b) + 1
    assert (path[0], path[-1]) == (a, b)
    assert all(q in grid.neighbours(p) for p, q in itertools.pairwise(path))
    # The same route as the distance model's (same tie-breaking).
    np.testing.assert_array_equal(grid.xys(path), nav.path(tuple(cells[0]), tuple(cells[-1])))


def test_unreachable_cells_and_walls() -> None:
    grid = Grid.from_layout(Layout(np.array([[c == "@" for c in r] for r in ("..@..",)])))
    a, b = grid.cell(0, 0), grid.cell(4, 0)
    assert grid.field(b)[a] == -1
    with pytest.raises(LayoutError, match=r"no path from \(x=0, y=0\) to \(x=4, y=0\)"):
        grid.distance(a, b)
    open_row = ascii_grid(".....")
    reach = open_row.reachable(open_row.cell(0, 0), walls=[open_row.cell(2, 0)])
    assert reach.tolist() == [True, True, False, False, False]
    # The start counts as free even when it is walled.
    assert open_row.reachable(2, walls=[2]).all()


def test_field_cache_is_bounded() -> None:
    grid = Grid(np.ones((30, 30), dtype=bool), cache_mb=0.0)
    for c in range(100):
        grid.field(c)
    assert len(grid._fields) == 64
    assert grid.field(99)[0] == 99 % 30 + 99 // 30
