"""The simulator's options: one typed dataclass per layout, navigator and task stream.

Each dataclass is the schema of one Hydra option (``layout=shelves``, ``navigator=cbs``,
``tasks=designated``, ...): its fields are that option's keys and their defaults, written
here once. The YAML twins in ``rtaw_marl/conf/`` only point at these schemas
(:mod:`rtaw_marl.config.store` registers them), and plain Python code builds the same
objects by name (:func:`layout_option` and friends). Every option builds its part:
``LayoutOption.build() -> Layout``, ``NavigatorOption.distance_model(layout) -> DistanceModel``
plus ``NavigatorOption.executor()`` (``None``: robots travel independently),
``TaskOption.build() -> TaskStream``.

This package is plain Python (no Hydra, no torch): the config layer above imports it.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from rtaw_marl.errors import unknown_name
from rtaw_marl.sim.layout import Layout
from rtaw_marl.sim.maps import BUILTIN
from rtaw_marl.sim.options.base import Option, option_from
from rtaw_marl.sim.options.layouts import (
    LAYOUTS,
    FileLayoutConfig,
    GivenLayout,
    LayoutOption,
    LoRRLayoutConfig,
    OpenLayoutConfig,
    PresetLayoutConfig,
    ShelvesLayoutConfig,
    WarehouseLayoutConfig,
)
from rtaw_marl.sim.options.navigators import (
    NAVIGATORS,
    AStarConfig,
    CBSConfig,
    DirectConfig,
    NavigatorOption,
    PIBTConfig,
    SIPPConfig,
)
from rtaw_marl.sim.options.tasks import (
    TASK_STREAMS,
    ClusteredTasksConfig,
    DesignatedTasksConfig,
    FileTasksConfig,
    GivenTasks,
    LoRRTasksConfig,
    PocTasksConfig,
    RandomTasksConfig,
    StationTasksConfig,
    TaskOption,
    TwoTaskConfig,
)
from rtaw_marl.sim.tasks import TaskStream
from rtaw_marl.sim.warehouse_layouts import PRESETS

__all__ = [
    "LAYOUTS",
    "NAVIGATORS",
    "TASK_STREAMS",
    "AStarConfig",
    "CBSConfig",
    "ClusteredTasksConfig",
    "DesignatedTasksConfig",
    "DirectConfig",
    "FileLayoutConfig",
    "FileTasksConfig",
    "GivenLayout",
    "GivenTasks",
    "LayoutOption",
    "LoRRLayoutConfig",
    "LoRRTasksConfig",
    "NavigatorOption",
    "OpenLayoutConfig",
    "Option",
    "PIBTConfig",
    "PocTasksConfig",
    "PresetLayoutConfig",
    "RandomTasksConfig",
    "SIPPConfig",
    "ShelvesLayoutConfig",
    "StationTasksConfig",
    "TaskOption",
    "TwoTaskConfig",
    "WarehouseLayoutConfig",
    "layout_option",
    "navigator_option",
    "option_from",
    "task_option",
]


def layout_option(spec: str | Mapping[str, Any] | LayoutOption | Layout) -> LayoutOption:
    """A layout option from a name (``shelves``), a file path or ``builtin:NAME`` (a
    shipped map, :mod:`rtaw_marl.sim.maps`), a mapping, a :class:`Layout` or itself.

    The paper's warehouses are named as on the command line (``layout=C``): ``"C"`` and
    ``{"name": "C", "width": 256, "height": 256}`` are the ``preset`` option with
    ``preset="C"``.
    """
    if isinstance(spec, Layout):
        return GivenLayout(layout=spec)
    if isinstance(spec, str) and spec not in LAYOUTS and ("." in spec or spec.startswith(BUILTIN)):
        return FileLayoutConfig(path=spec)
    name = spec if isinstance(spec, str) else None
    if isinstance(spec, Mapping):
        name = spec.get("name")
    if name in PRESETS:
        keys = {} if isinstance(spec, str) else {k: v for k, v in spec.items() if k != "name"}
        return option_from(LAYOUTS, "layout", {"name": "preset", "preset": name, **keys})  # type: ignore[return-value]
    if isinstance(name, str) and name not in LAYOUTS:
        raise unknown_name("layout", name, [*LAYOUTS, *PRESETS])
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
