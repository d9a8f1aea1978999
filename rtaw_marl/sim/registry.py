"""Named layouts, navigators and task streams, built from plain config mappings.

Each option is a builder with explicit keyword parameters; a spec is a mapping with a
``name`` key plus those parameters (the Hydra ``layout``/``navigator``/``tasks`` groups
are such mappings). Unknown names and unknown parameters fail with the list of what exists.
"""

from __future__ import annotations

import inspect
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

from rtaw_marl.errors import ConfigError, unknown_name
from rtaw_marl.sim.core import SimConfig, WarehouseSim
from rtaw_marl.sim.layout import Layout, load_layout, open_grid, shelf_grid
from rtaw_marl.sim.navigation import AStarNavigator, DirectNavigator, Navigator
from rtaw_marl.sim.path_navigators import CBSNavigator, SIPPNavigator
from rtaw_marl.sim.tasks import (
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
    "build_sim",
    "make_layout",
    "make_navigator",
    "make_task_stream",
]


def _file_layout(path: str) -> Layout:
    return load_layout(path)


def _file_tasks(path: str) -> TaskStream:
    return load_task_csv(path)


LAYOUTS: dict[str, Callable[..., Layout]] = {
    "open": open_grid,
    "shelves": shelf_grid,
    "warehouse": warehouse_grid,
    "preset": warehouse_preset,
    "file": _file_layout,
}

NAVIGATORS: dict[str, Callable[..., Navigator]] = {
    "direct": DirectNavigator,
    "astar": AStarNavigator,
    "sipp": SIPPNavigator,
    "cbs": CBSNavigator,
}

TASK_STREAMS: dict[str, Callable[..., TaskStream]] = {
    "random": RandomTasks,
    "designated": DesignatedTasks,
    "clustered": ClusteredTasks,
    "stations": StationTasks,
    "file": _file_tasks,
    "poc": lambda: FixedTasks(POC_TASKS, name="poc tasks"),
    "two_task": lambda: FixedTasks(TWO_TASKS, refill_same_slot=True, name="two-task tasks"),
}


def make_layout(spec: str | Mapping[str, Any] | Layout) -> Layout:
    """Build a layout from a name, a file path, a ``{"name": ..., **params}`` mapping or a Layout.

    A mapping with a non-null ``path`` loads that file whatever its ``name``.
    """
    if isinstance(spec, Layout):
        return spec
    if isinstance(spec, str):
        if spec in LAYOUTS and spec not in ("file", "preset"):
            return LAYOUTS[spec]()
        if Path(spec).suffix:
            return load_layout(spec)
        raise unknown_name("layout", spec, [k for k in LAYOUTS if k not in ("file", "preset")])
    params = dict(spec)
    path = params.pop("path", None)
    name = params.pop("name", None)
    if path is not None:
        return load_layout(path)
    if name is None:
        raise ConfigError("layout config needs a 'name' (or a 'path')")
    return _call("layout", LAYOUTS, name, params)


def make_navigator(spec: str | Mapping[str, Any], layout: Layout) -> Navigator:
    """Build a navigator for ``layout`` from a name or a ``{"name": ..., **params}`` mapping.

    Raises:
        ConfigError: The name is not registered (the message lists those that are) or a
            parameter is unknown.
    """
    params = {"name": spec} if isinstance(spec, str) else dict(spec)
    name = params.pop("name", None)
    if name is None:
        raise ConfigError("navigator config needs a 'name'")
    if name not in NAVIGATORS:
        raise unknown_name("navigator", name, list(NAVIGATORS))
    return _call("navigator", NAVIGATORS, name, {"layout": layout, **params})


def make_task_stream(spec: str | Mapping[str, Any] | TaskStream) -> TaskStream:
    """Build a task stream from a name, a ``{"name": ..., **params}`` mapping or a TaskStream."""
    if isinstance(spec, TaskStream):
        return spec
    if isinstance(spec, str):
        return _call("task stream", TASK_STREAMS, spec, {})
    params = dict(spec)
    name = params.pop("name", None)
    if name is None:
        raise ConfigError("tasks config needs a 'name'")
    return _call("task stream", TASK_STREAMS, name, params)


def build_sim(
    env: Mapping[str, Any] | SimConfig,
    layout: str | Mapping[str, Any] | Layout,
    navigator: str | Mapping[str, Any],
    tasks: str | Mapping[str, Any] | TaskStream,
) -> WarehouseSim:
    """Build a :class:`WarehouseSim` from config values.

    Args:
        env: :class:`SimConfig` or a mapping of its fields (the ``env.*`` keys).
        layout: Layout spec (see :func:`make_layout`).
        navigator: Navigator name (``direct``, ``astar``, ``sipp``, ``cbs``) or mapping.
        tasks: Task stream spec (see :func:`make_task_stream`).
    """
    config = env if isinstance(env, SimConfig) else sim_config(env)
    grid = make_layout(layout)
    return WarehouseSim(config, grid, make_navigator(navigator, grid), make_task_stream(tasks))


def sim_config(values: Mapping[str, Any]) -> SimConfig:
    """A :class:`SimConfig` from a mapping; unknown keys are an error naming them."""
    allowed = set(inspect.signature(SimConfig).parameters)
    unknown = sorted(set(values) - allowed)
    if unknown:
        raise ConfigError(f"unknown env keys {unknown}; available: {', '.join(sorted(allowed))}")
    return SimConfig(**dict(values))


def _call(kind: str, registry: Mapping[str, Callable[..., Any]], name: str, params: dict) -> Any:
    try:
        builder = registry[name]
    except KeyError:
        raise unknown_name(kind, name, list(registry)) from None
    allowed = set(inspect.signature(builder).parameters)
    unknown = sorted(set(params) - allowed)
    if unknown:
        raise ConfigError(
            f"unknown parameters {unknown} for {kind} {name!r}; "
            f"available: {', '.join(sorted(allowed)) or 'none'}"
        )
    missing = [
        p.name
        for p in inspect.signature(builder).parameters.values()
        if p.default is inspect.Parameter.empty and p.name not in params
    ]
    if missing or any(v is None and k in missing for k, v in params.items()):
        raise ConfigError(f"{kind} {name!r} needs {', '.join(missing)}")
    for key, value in params.items():
        if value is None:
            raise ConfigError(f"{kind} {name!r}: parameter {key!r} must be set")
    return builder(**params)
