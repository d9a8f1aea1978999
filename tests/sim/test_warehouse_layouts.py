"""The parametric warehouse generator, the paper's layouts A-E, stations and task streams."""

from __future__ import annotations

import numpy as np
import pytest

from rtaw_marl.errors import ConfigError, LayoutError
from rtaw_marl.sim.layout import Layout
from rtaw_marl.sim.options import PresetLayoutConfig, WarehouseLayoutConfig, layout_option
from rtaw_marl.sim.tasks import ClusteredTasks, StationTasks
from rtaw_marl.sim.warehouse_layouts import PRESETS

pytestmark = pytest.mark.unit

COMPACTNESS = {"A": 0.13, "B": 0.56, "C": 0.28, "D": 0.49, "E": 0.24}


@pytest.mark.parametrize("preset", sorted(PRESETS))
def test_presets_are_connected_deterministic_and_pinned(preset: str) -> None:
    a, b = PresetLayoutConfig(preset=preset).build(), PresetLayoutConfig(preset=preset).build()
    assert np.array_equal(a.obstacles, b.obstacles)
    assert (a.width, a.height) == (60, 60)
    assert a.num_components == 1
    assert a.compactness == pytest.approx(COMPACTNESS[preset], abs=0.01)


def test_compactness_levels_match_the_paper() -> None:
    """A very low, C and E low, B and D high (the paper's Fig. "layouts")."""
    c = {p: PresetLayoutConfig(preset=p).build().compactness for p in PRESETS}
    assert c["A"] < min(c["C"], c["E"])
    assert max(c["C"], c["E"]) < min(c["B"], c["D"])


def test_any_size_layout_c_256() -> None:
    layout = layout_option({"name": "preset", "preset": "C", "width": 256, "height": 256}).build()
    assert (layout.width, layout.height) == (256, 256)
    assert layout.num_components == 1
    assert 0.2 < layout.compactness < 0.4


def test_stations_are_free_and_where_documented() -> None:
    layout = WarehouseLayoutConfig(
        width=40, height=30, shelf_width=5, shelf_height=2, margin=2, station_spacing=3
    ).build()
    pickup, delivery = layout.station_cells("pickup"), layout.station_cells("delivery")
    assert len(pickup)
    assert len(delivery)
    assert layout.is_free(pickup).all()
    assert layout.is_free(delivery).all()
    # Pickup cells touch a shelf; delivery cells sit in the edge columns every 3 rows.
    padded = np.pad(layout.obstacles, 1)
    touching = [
        padded[y + 1 + dy, x + 1 + dx]
        for x, y in pickup
        for dy, dx in ((0, 1), (0, -1), (1, 0), (-1, 0))
    ]
    assert np.asarray(touching).reshape(-1, 4).any(axis=1).all()
    assert set(delivery[:, 0]) == {0, 39}
    assert set(delivery[:, 1]) == set(range(2, 30, 3))


def test_station_on_obstacle_and_bad_masks_are_reported() -> None:
    grid = np.zeros((3, 4), dtype=bool)
    grid[1, 2] = True
    mask = np.zeros_like(grid)
    mask[1, 2] = True
    with pytest.raises(LayoutError, match=r"pickup station at \(x=2, y=1\) is on an obstacle"):
        Layout(grid, name="t", pickup=mask)
    with pytest.raises(LayoutError, match="delivery mask"):
        Layout(grid, name="t", delivery=np.zeros((2, 2), dtype=bool))


def test_describe_reports_disconnected_regions() -> None:
    grid = np.zeros((3, 7), dtype=bool)
    grid[:, 3] = True
    text = Layout(grid, name="split").describe()
    assert "2 regions" in text
    assert "9 free cells elsewhere are never used" in text


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"shelf_width": 0}, "layout.shelf_width must be >= 1"),
        ({"highway_every": -1}, "layout.highway_every must be >= 0"),
        ({"width": 5, "height": 5, "shelf_width": 8}, "no 8x2 shelf fits"),
    ],
)
def test_bad_generator_parameters(kwargs: dict, message: str) -> None:
    with pytest.raises(LayoutError, match=message):
        WarehouseLayoutConfig(**kwargs).build()


def test_unknown_preset_lists_available() -> None:
    with pytest.raises(ConfigError, match="available: A, B, C, D, E"):
        PresetLayoutConfig(preset="F").build()


def test_clustered_tasks_move_with_the_seed() -> None:
    layout = PresetLayoutConfig(preset="C").build()
    stream = ClusteredTasks(num_clusters=3, sigma=2.0)
    a = stream.generate(np.random.default_rng(1), layout, 300)
    b = stream.generate(np.random.default_rng(1), layout, 300)
    c = stream.generate(np.random.default_rng(2), layout, 300)
    assert np.array_equal(a, b)
    assert not np.array_equal(a, c)
    assert layout.is_free(a[:, :2]).all()
    assert layout.is_free(a[:, 2:]).all()
    # Concentrated: far fewer distinct origin cells than uniform sampling would give.
    assert len({tuple(r) for r in a[:, :2]}) < 150


def test_station_tasks_use_the_stations() -> None:
    layout = PresetLayoutConfig(preset="B").build()
    tasks = StationTasks().generate(np.random.default_rng(0), layout, 200)
    pickup = {tuple(c) for c in layout.station_cells("pickup")}
    delivery = {tuple(c) for c in layout.station_cells("delivery")}
    assert all(tuple(o) in pickup for o in tasks[:, :2])
    assert all(tuple(d) in delivery for d in tasks[:, 2:])


def test_station_tasks_need_stations() -> None:
    with pytest.raises(ConfigError, match="marks no reachable pickup stations"):
        StationTasks().generate(np.random.default_rng(0), layout_option("shelves").build(), 10)


@pytest.mark.parametrize("preset", sorted(PRESETS))
def test_ascii_exports_in_docs_match_the_generator(preset: str) -> None:
    """docs/layouts/<P>.txt (written by benchmarks/scripts/export_layouts.py) is layout <P>."""
    from pathlib import Path

    from rtaw_marl.sim.layout import load_layout

    path = Path(__file__).resolve().parents[2] / "docs" / "layouts" / f"{preset}.txt"
    assert np.array_equal(
        load_layout(path).obstacles, PresetLayoutConfig(preset=preset).build().obstacles
    )
