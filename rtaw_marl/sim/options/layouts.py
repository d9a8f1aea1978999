"""Layout options (the ``layout`` config group): one dataclass per generator or file."""

from __future__ import annotations

import dataclasses
from abc import ABC, abstractmethod
from dataclasses import dataclass, field
from typing import ClassVar

from rtaw_marl.errors import ConfigError, LayoutError, unknown_name
from rtaw_marl.sim.layout import Layout, load_layout, open_grid, shelf_grid
from rtaw_marl.sim.lorr import read_problem
from rtaw_marl.sim.options.base import Option
from rtaw_marl.sim.warehouse_layouts import PRESETS, warehouse_grid
from rtaw_marl.utils.checks import at_least

__all__ = [
    "LAYOUTS",
    "FileLayoutConfig",
    "GivenLayout",
    "LayoutOption",
    "LoRRLayoutConfig",
    "OpenLayoutConfig",
    "PresetLayoutConfig",
    "ShelvesLayoutConfig",
    "WarehouseLayoutConfig",
]


@dataclass(kw_only=True)
class LayoutOption(Option, ABC):
    """A layout option.

    Attributes:
        path: A layout file (SBPL ``.cfg``, MovingAI ``.map`` or ASCII) loaded instead of
            the generated layout when set, with any ``layout=``; ``builtin:NAME`` loads a
            map shipped with the package (``builtin:usc_64.cfg``; names:
            ``rtaw_marl.sim.maps.MAPS``).
    """

    group: ClassVar[str] = "layout"
    path: str | None = None

    def build(self) -> Layout:
        """The layout this option describes."""
        if self.path is not None:
            return load_layout(self.path)
        return self._generate()

    def size(self) -> tuple[int, int] | None:
        """``(width, height)`` of the layout before it is built, or ``None`` when only
        building tells (a file); the builder refuses a size that cannot fit in memory."""
        width, height = getattr(self, "width", None), getattr(self, "height", None)
        if self.path is not None or width is None or height is None:
            return None
        return int(width), int(height)

    @abstractmethod
    def _generate(self) -> Layout:
        """The generated layout (used when ``path`` is not set)."""


@dataclass(kw_only=True)
class OpenLayoutConfig(LayoutOption):
    """An obstacle-free grid (the paper's "Direct" setting).

    Attributes:
        width: Columns.
        height: Rows.
    """

    name: str = "open"
    width: int = 60
    height: int = 60

    def __post_init__(self) -> None:
        super().__post_init__()
        at_least(self, "layout.", 1, "width", "height", error=LayoutError)

    def _generate(self) -> Layout:
        return open_grid(self.width, self.height)


@dataclass(kw_only=True)
class ShelvesLayoutConfig(LayoutOption):
    """Rows of shelf blocks separated by aisles.

    Attributes:
        width: Columns.
        height: Rows.
        shelf_width: Shelf block width in cells.
        shelf_height: Shelf block height in cells.
        aisle: Free cells between blocks.
        margin: Free cells along the edges.
    """

    name: str = "shelves"
    width: int = 60
    height: int = 60
    shelf_width: int = 8
    shelf_height: int = 2
    aisle: int = 2
    margin: int = 3

    def __post_init__(self) -> None:
        super().__post_init__()
        sizes = ("width", "height", "shelf_width", "shelf_height", "aisle", "margin")
        at_least(self, "layout.", 1, *sizes, error=LayoutError)

    def _generate(self) -> Layout:
        return shelf_grid(
            self.width, self.height, self.shelf_width, self.shelf_height, self.aisle, self.margin
        )


@dataclass(kw_only=True)
class WarehouseLayoutConfig(LayoutOption):
    """The parametric warehouse generator (shelf blocks, aisles, highways, stations).

    Attributes:
        width: Columns.
        height: Rows.
        shelf_width: Shelf block width in cells.
        shelf_height: Shelf block height in cells.
        aisle_x: Free columns between blocks.
        aisle_y: Free rows between blocks.
        highway_every: Widen every k-th aisle to ``highway_width`` (0: no highways).
        highway_width: Width of a highway in cells.
        margin: Free cells along the edges.
        station_spacing: Rows between delivery stations in the edge columns.
    """

    name: str = "warehouse"
    width: int = 60
    height: int = 60
    shelf_width: int = 8
    shelf_height: int = 2
    aisle_x: int = 2
    aisle_y: int = 2
    highway_every: int = 0
    highway_width: int = 3
    margin: int = 2
    station_spacing: int = 4

    def __post_init__(self) -> None:
        super().__post_init__()
        sizes = ("width", "height", "shelf_width", "shelf_height", "aisle_x", "aisle_y")
        at_least(self, "layout.", 1, *sizes, error=LayoutError)
        others = ("highway_width", "margin", "station_spacing")
        at_least(self, "layout.", 1, *others, error=LayoutError)
        at_least(self, "layout.", 0, "highway_every", error=LayoutError)

    def _generate(self) -> Layout:
        return self.generate()

    def generate(self, name: str | None = None) -> Layout:
        """The generated layout, labelled ``name`` (default: from its size)."""
        params = {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}
        del params["name"], params["path"]
        return warehouse_grid(**params, name=name)


@dataclass(kw_only=True)
class PresetLayoutConfig(LayoutOption):
    """One of the paper's warehouses, generated at any size.

    Attributes:
        preset: ``A``-``E`` (the paper's compactness levels; docs/simulator.md).
        width: Columns.
        height: Rows.
    """

    name: str = "preset"
    preset: str
    width: int = 60
    height: int = 60

    def __post_init__(self) -> None:
        super().__post_init__()
        at_least(self, "layout.", 1, "width", "height", error=LayoutError)

    def _generate(self) -> Layout:
        if self.preset not in PRESETS:
            raise unknown_name("layout preset", self.preset, list(PRESETS))
        generator = WarehouseLayoutConfig(
            width=self.width, height=self.height, **PRESETS[self.preset]
        )
        return generator.generate(name=f"layout_{self.preset}_{self.width}x{self.height}")


@dataclass(kw_only=True)
class FileLayoutConfig(LayoutOption):
    """A layout file: SBPL ``.cfg``, MovingAI ``.map`` or ASCII (``.`` free, ``@`` blocked).

    Attributes:
        path: The file (required), or ``builtin:NAME`` for a shipped map
            (``builtin:warehouse-10-20-10-2-1.map``).
    """

    name: str = "file"
    path: str | None = field()  # required: no default

    def _generate(self) -> Layout:
        raise ConfigError("layout=file needs layout.path=FILE")


@dataclass(kw_only=True)
class LoRRLayoutConfig(LayoutOption):
    """The map of a League of Robot Runners 2024 problem (:mod:`rtaw_marl.sim.lorr`).

    Attributes:
        problem: The problem JSON (required; ``scenario=lorr`` takes ``tasks.problem``),
            or ``builtin:random_32_32_20_100.json``, the shipped one.
    """

    name: str = "lorr"
    problem: str | None = None

    def _generate(self) -> Layout:
        if self.problem is None:
            raise ConfigError("layout=lorr needs layout.problem=FILE.json (a LoRR problem)")
        return read_problem(self.problem).layout()


@dataclass(kw_only=True)
class GivenLayout(LayoutOption):
    """A :class:`Layout` built in Python (not a Hydra option: it is not serializable)."""

    name: str = "given"
    layout: Layout

    def _generate(self) -> Layout:
        return self.layout


LAYOUTS: dict[str, type[LayoutOption]] = {
    cls.__dataclass_fields__["name"].default: cls
    for cls in (
        OpenLayoutConfig,
        ShelvesLayoutConfig,
        WarehouseLayoutConfig,
        PresetLayoutConfig,
        FileLayoutConfig,
        LoRRLayoutConfig,
    )
}
