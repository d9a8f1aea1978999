"""A parametric warehouse layout generator and the paper's layouts A-E.

In the spirit of Asprilo's generator: rectangular shelf blocks tiled in rows and columns,
separated by aisles, with optional *highways* (every ``highway_every``-th aisle widened to
``highway_width``), a free margin along the edges, and stations:

* **pickup** stations: free cells next to a shelf (where a robot picks a shelf's goods);
* **delivery** stations: cells of the left and right margin columns, every
  ``station_spacing`` rows (picking/packing stations at the edges).

Deterministic from its parameters, any size. The paper's Fig. "layouts" shows five 60x60
Asprilo layouts by compactness (A very low, B high, C low, D high, E low); the presets
below reproduce those levels of compactness with different shelf shapes (the paper gives
no parameters). Compactness (blocked fraction) at 60x60: A 0.13, B 0.56, C 0.28, D 0.49,
E 0.24 (``tests/sim/test_warehouse_layouts.py`` pins them).
"""

from __future__ import annotations

import numpy as np

from rtaw_marl.errors import LayoutError
from rtaw_marl.sim.layout import Layout, check_sizes

__all__ = ["PRESETS", "warehouse_grid"]

_FOUR = ((0, 1), (0, -1), (1, 0), (-1, 0))

#: The paper's five layouts (Fig. "layouts"), as generator parameters.
#: The paper's layouts A-E as generator parameters, on top of the defaults of
#: :class:`rtaw_marl.sim.options.WarehouseLayoutConfig` (``layout=A`` ... ``layout=E``).
PRESETS: dict[str, dict[str, int]] = {
    # very low compactness: small square shelves, wide aisles
    "A": {"shelf_width": 2, "shelf_height": 2, "aisle_x": 3, "aisle_y": 3},
    # high compactness: long double rows, one-cell aisles, a highway every 3 columns
    "B": {"shelf_width": 10, "shelf_height": 4, "aisle_x": 1, "aisle_y": 1, "highway_every": 3},
    # low compactness: short rows, two-cell aisles
    "C": {"shelf_width": 4, "shelf_height": 2, "aisle_x": 2, "aisle_y": 2},
    # high compactness: deep blocks, one-cell aisles, highways every 2 blocks
    "D": {"shelf_width": 6, "shelf_height": 6, "aisle_x": 1, "aisle_y": 1, "highway_every": 2},
    # low compactness: vertical shelf columns, highways every 4 columns
    "E": {"shelf_width": 2, "shelf_height": 8, "aisle_x": 3, "aisle_y": 3, "highway_every": 4},
}


def _positions(length: int, block: int, aisle: int, margin: int, every: int, wide: int) -> list:
    """Start coordinates of the blocks along one axis, centred in ``length``."""
    starts, pos, count = [], 0, 0
    while True:
        if starts:
            count += 1
            pos += wide if every and count % every == 0 else aisle
        if pos + block > length - 2 * margin:
            break
        starts.append(pos)
        pos += block
    if not starts:
        return []
    used = starts[-1] + block
    offset = (length - used) // 2
    return [s + offset for s in starts]


def warehouse_grid(
    width: int,
    height: int,
    shelf_width: int,
    shelf_height: int,
    aisle_x: int,
    aisle_y: int,
    highway_every: int,
    highway_width: int,
    margin: int,
    station_spacing: int,
    name: str | None = None,
) -> Layout:
    """Generate a warehouse layout with shelves, aisles, highways and stations.

    Args:
        width: Grid columns ``W``.
        height: Grid rows ``H``.
        shelf_width: Columns per shelf block.
        shelf_height: Rows per shelf block.
        aisle_x: Free columns between neighbouring blocks.
        aisle_y: Free rows between neighbouring blocks.
        highway_every: Widen every this-many-th aisle to ``highway_width`` (0: none).
        highway_width: Width of a highway.
        margin: Free cells along every edge (at least 1, so all aisles connect).
        station_spacing: Rows between delivery stations in the edge columns.
        name: Label; defaults to the parameters' summary.

    Raises:
        LayoutError: A parameter is out of range or no shelf fits.
    """
    ints = {
        "width": width, "height": height, "shelf_width": shelf_width,
        "shelf_height": shelf_height, "aisle_x": aisle_x, "aisle_y": aisle_y,
        "highway_width": highway_width, "margin": margin, "station_spacing": station_spacing,
    }  # fmt: skip
    check_sizes(**ints)
    check_sizes(0, highway_every=highway_every)
    xs = _positions(width, shelf_width, aisle_x, margin, highway_every, highway_width)
    ys = _positions(height, shelf_height, aisle_y, margin, highway_every, highway_width)
    if not xs or not ys:
        raise LayoutError(
            f"no {shelf_width}x{shelf_height} shelf fits in {width}x{height} with margin {margin}"
        )
    grid = np.zeros((height, width), dtype=bool)
    for y0 in ys:
        for x0 in xs:
            grid[y0 : y0 + shelf_height, x0 : x0 + shelf_width] = True
    # Pickup stations: free cells with a shelf among their 4 neighbours.
    padded = np.pad(grid, 1)
    near_shelf = np.zeros_like(grid)
    for dy, dx in _FOUR:
        near_shelf |= padded[1 + dy : 1 + dy + height, 1 + dx : 1 + dx + width]
    pickup = near_shelf & ~grid
    delivery = np.zeros_like(grid)
    delivery[margin::station_spacing, 0] = True
    delivery[margin::station_spacing, width - 1] = True
    delivery &= ~grid
    label = name or f"warehouse_{width}x{height}"
    return Layout(grid, name=label, pickup=pickup, delivery=delivery)
