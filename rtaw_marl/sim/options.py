"""The simulator's options: one typed dataclass per layout, navigator and task stream.

Each dataclass is the schema of one Hydra option (``layout=shelves``, ``navigator=cbs``,
``tasks=designated``, ...): its fields are that option's keys and their defaults, written
here once. The YAML twins in ``rtaw_marl/conf/`` only point at these schemas
(:mod:`rtaw_marl.config.store` registers them), and plain Python code builds the same
objects by name (:func:`layout_option` and friends). Every option builds its part:
``LayoutOption.build() -> Layout``, ``NavigatorOption.navigator(layout) -> Navigator``
plus ``NavigatorOption.executor()`` (``None``: robots travel independently),
``TaskOption.build() -> TaskStream``.

This module is plain Python (no Hydra, no torch): the config layer above imports it.
"""

from __future__ import annotations

import dataclasses
from abc import ABC, abstractmethod
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, ClassVar

from rtaw_marl.errors import ConfigError, unknown_name
from rtaw_marl.sim.execution import Executor
from rtaw_marl.sim.layout import Layout, load_layout, open_grid, shelf_grid
from rtaw_marl.sim.mapf import CBSExecutor, SIPPExecutor
from rtaw_marl.sim.navigation import AStarNavigator, DirectNavigator, Navigator
from rtaw_marl.sim.tasks import (
    DEFAULT_CENTRES,
    POC_TASKS,
    TWO_TASKS,
    ClusteredTasks,
    DesignatedTasks,
    FixedTasks,
    RandomTasks,
    StationTasks,
    TaskStream,
    load_task_csv,
)
from rtaw_marl.sim.warehouse_layouts import warehouse_grid, warehouse_preset

__all__ = [
    "LAYOUTS",
    "NAVIGATORS",
    "TASK_STREAMS",
    "LayoutOption",
    "NavigatorOption",
    "TaskOption",
    "layout_option",
    "navigator_option",
    "option_from",
    "task_option",
]


@dataclass(kw_only=True)
class _Option:
    """Shared by every option.

    Attributes:
        name: The option's registry name (fixed by the option; choose an option with
            ``group=NAME``).
    """

    name: str

    def __post_init__(self) -> None:
        expected = type(self).__dataclass_fields__["name"].default
        if self.name != expected:
            raise ConfigError(
                f"{self.group}.name is {self.name!r} but the keys are those of {expected!r}; "
                f"choose another option with {self.group}=NAME instead"
            )

    group: ClassVar[str] = ""


# --------------------------------------------------------------------------- layouts
@dataclass(kw_only=True)
class LayoutOption(_Option, ABC):
    """A layout option.

    Attributes:
        path: A layout file (SBPL ``.cfg``, MovingAI ``.map`` or ASCII) loaded instead of
            the generated layout when set, with any ``layout=``.
    """

    group: ClassVar[str] = "layout"
    path: str | None = None

    def build(self) -> Layout:
        """The layout this option describes."""
        if self.path is not None:
            return load_layout(self.path)
        return self._generate()

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

    def _generate(self) -> Layout:
        params = {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}
        del params["name"], params["path"]
        return warehouse_grid(**params)


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

    def _generate(self) -> Layout:
        return warehouse_preset(self.preset, self.width, self.height)


@dataclass(kw_only=True)
class FileLayoutConfig(LayoutOption):
    """A layout file: SBPL ``.cfg``, MovingAI ``.map`` or ASCII (``.`` free, ``@`` blocked).

    Attributes:
        path: The file (required).
    """

    name: str = "file"
    path: str | None = field()  # required: no default

    def _generate(self) -> Layout:
        raise ConfigError("layout=file needs layout.path=FILE")


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
    )
}


# --------------------------------------------------------------------------- navigators
@dataclass(kw_only=True)
class NavigatorOption(_Option):
    """A navigator option: the distance model the policies observe, and how robots travel
    (independently, or executed collision-free by a path-planning fleet)."""

    group: ClassVar[str] = "navigator"
    #: Whether robots occupy cells and wait for each other.
    collision_aware: ClassVar[bool] = False

    def navigator(self, layout: Layout) -> Navigator:
        """The distance model on ``layout`` (shared by every simulator of a batch)."""
        return AStarNavigator(layout)

    def executor(self) -> Executor | None:
        """A fresh executor for one simulator; ``None`` means instant, independent travel."""
        return None


@dataclass(kw_only=True)
class DirectConfig(NavigatorOption):
    """Euclidean distances, obstacles ignored (the paper's "Direct" navigation)."""

    name: str = "direct"

    def navigator(self, layout: Layout) -> Navigator:
        return DirectNavigator(layout)


@dataclass(kw_only=True)
class AStarConfig(NavigatorOption):
    """True 4-connected shortest paths (cached BFS distance fields)."""

    name: str = "astar"


@dataclass(kw_only=True)
class SIPPConfig(NavigatorOption):
    """Collision-aware: prioritized Safe Interval Path Planning on the shared grid; the
    policy observes A* distances.

    Attributes:
        time_limit: Seconds one planning call may take before the run stops with an error.
    """

    name: str = "sipp"
    collision_aware: ClassVar[bool] = True
    time_limit: float = 10.0

    def __post_init__(self) -> None:
        super().__post_init__()
        _check_positive("navigator.time_limit", self.time_limit, "number", float)

    def executor(self) -> Executor:
        return SIPPExecutor(time_limit=self.time_limit)


@dataclass(kw_only=True)
class CBSConfig(NavigatorOption):
    """Collision-aware: Conflict-Based Search over all moving robots, re-planned at each
    assignment; the policy observes A* distances.

    Attributes:
        time_limit: Seconds one planning call may take before the run stops with an error.
        max_nodes: High-level CBS nodes per call; past it the new robot plans alone around
            the others (a deterministic budget; docs/simulator.md).
    """

    name: str = "cbs"
    collision_aware: ClassVar[bool] = True
    time_limit: float = 10.0
    max_nodes: int = 200

    def __post_init__(self) -> None:
        super().__post_init__()
        _check_positive("navigator.time_limit", self.time_limit, "number", float)
        _check_positive("navigator.max_nodes", self.max_nodes, "integer", int)

    def executor(self) -> Executor:
        return CBSExecutor(time_limit=self.time_limit, max_nodes=self.max_nodes)


def _check_positive(key: str, value: object, what: str, kind: type) -> None:
    numeric = (int,) if kind is int else (int, float)
    ok = isinstance(value, numeric) and not isinstance(value, bool)
    if not ok or not 0 < value < float("inf"):  # type: ignore[operator]
        raise ConfigError(f"{key} must be a positive {what}, got {value!r}")


NAVIGATORS: dict[str, type[NavigatorOption]] = {
    cls.__dataclass_fields__["name"].default: cls
    for cls in (DirectConfig, AStarConfig, SIPPConfig, CBSConfig)
}


# --------------------------------------------------------------------------- task streams
@dataclass(kw_only=True)
class TaskOption(_Option, ABC):
    """A task-stream option."""

    group: ClassVar[str] = "tasks"

    @abstractmethod
    def build(self) -> TaskStream:
        """The task stream this option describes."""


@dataclass(kw_only=True)
class RandomTasksConfig(TaskOption):
    """Origin and destination uniform over the free cells."""

    name: str = "random"

    def build(self) -> TaskStream:
        return RandomTasks()


@dataclass(kw_only=True)
class DesignatedTasksConfig(TaskOption):
    """Gaussian pickup and delivery regions around fixed centres.

    Attributes:
        pickup_centres: ``[x, y]`` centres of the pickup regions (default: the original
            RTAW code's five centres).
        delivery_centres: ``[x, y]`` centres of the delivery regions.
        sigma: Standard deviation of every region, in cells.
    """

    name: str = "designated"
    pickup_centres: list[list[float]] = field(default_factory=lambda: _centres())
    delivery_centres: list[list[float]] = field(default_factory=lambda: _centres())
    sigma: float = 5.0

    def build(self) -> TaskStream:
        return DesignatedTasks(self.pickup_centres, self.delivery_centres, self.sigma)


@dataclass(kw_only=True)
class ClusteredTasksConfig(TaskOption):
    """Tasks around cluster centres drawn per episode on free cells.

    Attributes:
        num_clusters: Number of clusters.
        sigma: Standard deviation of every cluster, in cells.
    """

    name: str = "clustered"
    num_clusters: int = 5
    sigma: float = 4.0

    def build(self) -> TaskStream:
        return ClusteredTasks(self.num_clusters, self.sigma)


@dataclass(kw_only=True)
class StationTasksConfig(TaskOption):
    """Pickup at the layout's pickup stations, delivery at its delivery stations (needs a
    generated warehouse layout: ``layout=A``..``E`` or ``warehouse``)."""

    name: str = "stations"

    def build(self) -> TaskStream:
        return StationTasks()


@dataclass(kw_only=True)
class FileTasksConfig(TaskOption):
    """A fixed task list: CSV with header ``ox,oy,dx,dy``, one task per row in arrival order.

    Attributes:
        path: The CSV file (required).
    """

    name: str = "file"
    path: str = field()  # required: no default

    def build(self) -> TaskStream:
        return load_task_csv(self.path)


@dataclass(kw_only=True)
class PocTasksConfig(TaskOption):
    """The paper's proof-of-concept list of 5 tasks (appendix)."""

    name: str = "poc"

    def build(self) -> TaskStream:
        return FixedTasks(POC_TASKS, name="poc tasks")


@dataclass(kw_only=True)
class TwoTaskConfig(TaskOption):
    """The paper's two-task setting: the queue always holds (0,0)->(3,3) and (0,0)->(9,9)."""

    name: str = "two_task"

    def build(self) -> TaskStream:
        return FixedTasks(TWO_TASKS, refill_same_slot=True, name="two-task tasks")


@dataclass(kw_only=True)
class GivenTasks(TaskOption):
    """A :class:`TaskStream` built in Python (not a Hydra option: it is not serializable)."""

    name: str = "given"
    stream: TaskStream

    def build(self) -> TaskStream:
        return self.stream


TASK_STREAMS: dict[str, type[TaskOption]] = {
    cls.__dataclass_fields__["name"].default: cls
    for cls in (
        RandomTasksConfig,
        DesignatedTasksConfig,
        ClusteredTasksConfig,
        StationTasksConfig,
        FileTasksConfig,
        PocTasksConfig,
        TwoTaskConfig,
    )
}


def _centres() -> list[list[float]]:
    return [[float(x), float(y)] for x, y in DEFAULT_CENTRES]


# --------------------------------------------------------------------------- by name
def option_from(
    registry: Mapping[str, type[_Option]], group: str, spec: str | Mapping[str, Any] | _Option
) -> _Option:
    """An option of ``registry`` from a name, a ``{"name": ..., **keys}`` mapping or itself.

    Raises:
        ConfigError: The name or a key is unknown (the message lists the valid ones), or a
            required key is missing.
    """
    if isinstance(spec, _Option):
        return spec
    params = {"name": spec} if isinstance(spec, str) else dict(spec)
    name = params.get("name")
    if name is None:
        raise ConfigError(f"{group} config needs a 'name'; available: {', '.join(registry)}")
    if name not in registry:
        raise unknown_name(group, str(name), list(registry))
    cls = registry[name]
    keys = [f.name for f in dataclasses.fields(cls)]
    unknown = sorted(set(params) - set(keys))
    if unknown:
        raise ConfigError(
            f"unknown key {group}.{unknown[0]} for {group}={name}; valid keys: "
            f"{', '.join(k for k in keys if k != 'name') or 'none'}"
        )
    required = [
        f.name
        for f in dataclasses.fields(cls)
        if f.default is dataclasses.MISSING
        and f.default_factory is dataclasses.MISSING
        and params.get(f.name) is None
    ]
    if required:
        raise ConfigError(f"{group}={name} needs {group}.{required[0]}=...")
    return cls(**params)


def layout_option(spec: str | Mapping[str, Any] | LayoutOption | Layout) -> LayoutOption:
    """A layout option from a name (``shelves``), a file path, a mapping, a
    :class:`Layout` or itself."""
    if isinstance(spec, Layout):
        return GivenLayout(layout=spec)
    if isinstance(spec, str) and spec not in LAYOUTS and "." in spec:
        return FileLayoutConfig(path=spec)
    return option_from(LAYOUTS, "layout", spec)  # type: ignore[return-value]


def navigator_option(spec: str | Mapping[str, Any] | NavigatorOption) -> NavigatorOption:
    """A navigator option from a name (``astar``), a mapping or itself."""
    return option_from(NAVIGATORS, "navigator", spec)  # type: ignore[return-value]


def task_option(spec: str | Mapping[str, Any] | TaskOption | TaskStream) -> TaskOption:
    """A task-stream option from a name (``designated``), a mapping, a
    :class:`TaskStream` or itself."""
    if isinstance(spec, TaskStream):
        return GivenTasks(stream=spec)
    return option_from(TASK_STREAMS, "tasks", spec)  # type: ignore[return-value]
