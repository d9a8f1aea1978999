"""``tasks=designated`` on any map size: the original code's centres, written for a 60x60
area, scale to other layouts; on the 60x60 and 64x64 grids they were made for, the task
streams are exactly those the shipped results were made with."""

from __future__ import annotations

import hashlib

import numpy as np
import pytest

from rtaw_marl.sim.layout import Layout, load_layout, open_grid
from rtaw_marl.sim.options import DesignatedTasksConfig, layout_option
from rtaw_marl.sim.tasks import DEFAULT_CENTRES, DesignatedTasks, default_centres

pytestmark = pytest.mark.unit

#: sha256 of the tasks of seeds 0-4 (1,000 each, ``int64`` bytes in seed order), recorded
#: with the code before centres were scaled (commit f8b0fca).
STREAMS = {
    "shelves": "25cea103d5ad90e0d1fa5b08cadc42dc6b21a0529a6b6e402708a4c52c99e2c1",
    "open": "3453d10b408810792baca5b1ccf797d43b384fb61d8eb434eac90b7ff49b61a5",
    "A": "c56d7d3a4b995ce3c9a707d72c8ad452aaa08bb4853c38e41655ddd1f8bb33ce",
    "B": "de3d0118907f8412e6e0af9d7918430e6e0a78ac6093bf44b55b3eb096a4c16f",
    "C": "f7b1380ce69c5bccc1865d829ddba6c9076ea48850568474af970bb892ed1207",
    "D": "4cc8017062e9a9c9235c13a3e3bf46917b03994f47f1dbcb7dba283ab5f25f13",
    "E": "a90f6fc2be5dbe7f29ce72eb9542364f97e99fa973a123872f9022ffbf691c8d",
    "builtin:open_64.cfg": "fd29048af9352e7988043c3fdf3aabdc26e3bfa4bfc0cef42754918f81da382b",
    "builtin:usc_64.cfg": "fa48397fd7662d6c2e7300b44f5a789fe59740bd6a7f8b4201f213af314d002a",
    "builtin:tight_64.cfg": "360ee464e9968053671a2c8d06f1be33f054c62a8e62c4c59893257027908aed",
    "builtin:tight_2_64.cfg": "f8807ec9a1872e71ef87993877406b16edfdac580716d0b7f4a23bb5482870df",
    "builtin:compact_64.cfg": "f3df0045c1756d61d5cae080a639f63b5744437cc8dceb405bbcd96f43453b81",
    "builtin:compact_2_64.cfg": "9a7ef08913bdf848057a8df69b857e177fae08eab64d8e038890b35b8bc5a73c",
}

MOVINGAI = "builtin:warehouse-10-20-10-2-1.map"


def _tasks(layout: Layout, seed: int, count: int = 1000) -> np.ndarray:
    return DesignatedTasksConfig().build().generate(np.random.default_rng(seed), layout, count)


@pytest.mark.parametrize("layout", sorted(STREAMS))
def test_streams_on_the_grids_they_were_made_for_are_unchanged(layout: str) -> None:
    """The default layout, Table I's six and the original code's six 64x64 maps: the
    same tasks, bit for bit, as before scaling existed."""
    grid = layout_option(layout).build()
    assert (grid.width, grid.height) in ((60, 60), (64, 64))
    digest = hashlib.sha256()
    for seed in range(5):
        tasks = _tasks(grid, seed)
        assert (tasks.dtype, tasks.shape) == (np.int64, (1000, 4))
        digest.update(tasks.tobytes())
    assert digest.hexdigest() == STREAMS[layout]


@pytest.mark.parametrize("size", [(60, 60), (64, 64), (60, 64), (62, 61)])
def test_centres_stay_as_written_along_sides_of_60_to_64(size: tuple[int, int]) -> None:
    assert default_centres(open_grid(*size)).tolist() == [
        list(map(float, c)) for c in DEFAULT_CENTRES
    ]


def test_tasks_span_a_wide_map() -> None:
    """161x63 MovingAI warehouse: before, every origin had x <= 62 (the 60x60 centres);
    now pickups and deliveries reach past 80% of the width, all on free main cells."""
    layout = load_layout(MOVINGAI)
    assert (layout.width, layout.height) == (161, 63)
    tasks = _tasks(layout, 0)
    main = {tuple(c) for c in layout.main_cells.tolist()}
    for ends in (tasks[:, :2], tasks[:, 2:]):
        assert ends[:, 0].max() > 0.8 * layout.width
        assert ends[:, 0].min() < 0.1 * layout.width
        assert ends[:, 1].max() > 0.8 * layout.height  # the 63 rows: kept as written
        assert layout.is_free(ends).all()
        assert {tuple(c) for c in ends.tolist()} <= main
    assert (tasks[:, :2] != tasks[:, 2:]).any(axis=1).all()


def test_scaling_is_proportional_per_side() -> None:
    """x' = (x + 0.5) W / 60 - 0.5 along a side outside 60-64; a side inside keeps y."""
    centres = np.array(DEFAULT_CENTRES, dtype=float)
    wide = default_centres(open_grid(120, 62))
    assert np.allclose(wide[:, 0], (centres[:, 0] + 0.5) * 2 - 0.5)
    assert np.array_equal(wide[:, 1], centres[:, 1])
    small = default_centres(open_grid(30, 30))
    assert np.allclose(small, (centres + 0.5) / 2 - 0.5)


def test_small_grid_uses_its_whole_area() -> None:
    """A 10x10 grid, where the unscaled centre (4, 54) was off the grid (an error
    before), gets the five regions scaled into it."""
    tasks = _tasks(open_grid(10, 10), 0, 500)
    assert (tasks.min(), tasks.max()) == (0, 9)
    assert (tasks[:, 0].max(), tasks[:, 1].max()) == (9, 9)


def test_a_scaled_centre_on_an_obstacle_moves_to_the_nearest_free_cell() -> None:
    """On 180x180 the first centre (11, 10) scales to the cell (34, 31) exactly; blocked,
    four cells are equally near, and the lowest row wins: (34, 30)."""
    grid = np.zeros((180, 180), dtype=bool)
    assert default_centres(Layout(grid))[0].tolist() == [34.0, 31.0]
    grid[31, 34] = True
    assert default_centres(Layout(grid))[0].tolist() == [34.0, 30.0]
    # A centre inside a small region (cut off from the main one) moves out of it too.
    grid = np.zeros((180, 180), dtype=bool)
    grid[29:34, 32:37] = True
    grid[31, 34] = False  # a 1-cell region around (34, 31)
    moved = default_centres(Layout(grid))[0]
    assert moved.tolist() == [34.0, 28.0]


def test_centres_on_the_movingai_map_are_free_and_near_their_scaled_place() -> None:
    """x scaled by 161/60 (y kept: 63 rows); the two centres that land in a shelf row
    move to a free neighbour."""
    layout = load_layout(MOVINGAI)
    centres = default_centres(layout)
    assert layout.is_free(np.rint(centres).astype(np.int64)).all()
    scaled = np.array(DEFAULT_CENTRES, dtype=float)
    scaled[:, 0] = (scaled[:, 0] + 0.5) * 161 / 60 - 0.5
    assert np.abs(centres - scaled).max() <= 1.0
    assert sum(not np.allclose(a, b) for a, b in zip(centres, scaled, strict=True)) == 2


def test_given_centres_are_cells_of_the_layout_never_scaled() -> None:
    """A centre the user gives is used as given on any map; only the default set scales."""
    layout = load_layout(MOVINGAI)
    stream = DesignatedTasksConfig(pickup_centres=[[30, 10]], sigma=1.0).build()
    assert isinstance(stream, DesignatedTasks)
    pickup, delivery = stream.centres(layout)
    assert pickup.tolist() == [[30.0, 10.0]]
    assert np.array_equal(delivery, default_centres(layout))
    tasks = stream.generate(np.random.default_rng(0), layout, 300)
    assert np.abs(tasks[:, :2].mean(axis=0) - (30, 10)).max() < 0.5
    assert tasks[:, 2].max() > 0.8 * layout.width
