"""The one builder: a simulator (or a batch of simulators) from a typed spec.

Every entry point assembles its simulators here: the PettingZoo env, the batched
TorchRL env, the trainer, ``rtaw-eval``, ``rtaw-render`` and the experiment scripts. A
:class:`SimSpec` holds the four config groups (``sim``, ``layout``, ``navigator``,
``tasks``) as typed options; :class:`SimFactory` builds the layout, the distance model and
the task stream once and makes any number of simulators sharing them (the distance
fields are cached per distance model), each with its own executor.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

from rtaw_marl.errors import ConfigError
from rtaw_marl.sim.budget import check_memory
from rtaw_marl.sim.config import SimBuffers, SimConfig
from rtaw_marl.sim.core import WarehouseSim
from rtaw_marl.sim.distances import DistanceModel
from rtaw_marl.sim.layout import Layout
from rtaw_marl.sim.options import (
    DirectConfig,
    LayoutOption,
    NavigatorOption,
    TaskOption,
    layout_option,
    navigator_option,
    task_option,
)
from rtaw_marl.sim.tasks import TaskStream

__all__ = ["SimFactory", "SimGroups", "SimSpec", "build_sim", "sim_config"]


#: The option of each simulator group when none is named: the default warehouse (60x60
#: shelves, A*, designated tasks). The commands' defaults lists take them from here
#: (``/setting/default`` in Hydra's ConfigStore), and :class:`SimSpec` builds them.
DEFAULT_OPTIONS: Mapping[str, str] = MappingProxyType(
    {"sim": "default", "layout": "shelves", "navigator": "astar", "tasks": "designated"}
)


@dataclass(kw_only=True)
class SimSpec:
    """Everything that defines a simulator: the ``sim``, ``layout``, ``navigator`` and
    ``tasks`` config groups, typed."""

    sim: SimConfig = field(default_factory=SimConfig)
    layout: LayoutOption = field(default_factory=lambda: layout_option(DEFAULT_OPTIONS["layout"]))
    navigator: NavigatorOption = field(
        default_factory=lambda: navigator_option(DEFAULT_OPTIONS["navigator"])
    )
    tasks: TaskOption = field(default_factory=lambda: task_option(DEFAULT_OPTIONS["tasks"]))

    @classmethod
    def of(
        cls,
        sim: SimConfig | Mapping[str, Any] | None = None,
        layout: str | Mapping[str, Any] | LayoutOption | None = None,
        navigator: str | Mapping[str, Any] | NavigatorOption | None = None,
        tasks: str | Mapping[str, Any] | TaskOption | None = None,
    ) -> SimSpec:
        """A spec from names, ``{"name": ..., **keys}`` mappings or typed options; a
        group left ``None`` takes its default. Simulator keys not in ``sim`` (a mapping)
        take the navigator's ``sim_defaults`` (SIPP and CBS turn the completion noise
        off), as ``navigator=sipp`` does on the command line.

        Raises:
            ConfigError: A name or key is unknown (listing the valid ones), or a value is
                invalid.
        """
        spec = cls()
        nav = spec.navigator if navigator is None else navigator_option(navigator)
        if not isinstance(sim, SimConfig):
            # What the navigator's YAML twin sets (SIPP/CBS: no noise), unless given.
            sim = {**nav.sim_defaults, **(sim or {})}
        return cls(
            sim=sim_config(sim),
            layout=spec.layout if layout is None else layout_option(layout),
            navigator=nav,
            tasks=spec.tasks if tasks is None else task_option(tasks),
        )

    def as_dict(self) -> dict[str, Any]:
        """Plain values (lists, not tuples) for results and checkpoints."""
        return _plain(dataclasses.asdict(self))


@dataclass(kw_only=True)
class SimGroups:
    """The four simulator groups of a run config (``rtaw-train``, ``rtaw-eval``,
    ``rtaw-render``), filled by Hydra with typed options.

    Attributes:
        sim: The simulator's keys (:class:`~rtaw_marl.sim.config.SimConfig`).
        layout: A layout option (:mod:`rtaw_marl.sim.options`).
        navigator: A navigator option.
        tasks: A task-stream option.
    """

    sim: Any
    layout: Any
    navigator: Any
    tasks: Any

    def sim_spec(self) -> SimSpec:
        """The typed spec the one builder takes."""
        return SimSpec.of(self.sim, self.layout, self.navigator, self.tasks)


class SimFactory:
    """Builds the shared parts of ``spec`` once, then simulators on demand.

    Attributes:
        spec: The spec.
        layout: The layout.
        distance_model: The distance model, shared by every simulator made here.
        tasks: The task stream (stateless; each simulator draws from its own seed).
    """

    def __init__(self, spec: SimSpec) -> None:
        self.spec = spec
        # Checked before anything is allocated: a generated layout's size is known up
        # front, a file's once it is read (its size is bounded by the file's).
        size = spec.layout.size()
        if size is not None:
            self._check_memory(*size, name=spec.layout.name)
        self.layout: Layout = spec.layout.build()
        self._check_memory(self.layout.width, self.layout.height, name=self.layout.name)
        self.distance_model: DistanceModel = spec.navigator.distance_model(self.layout)
        self.tasks: TaskStream = spec.tasks.build()

    def _check_memory(self, width: int, height: int, name: str) -> None:
        fields = not isinstance(self.spec.navigator, DirectConfig)
        check_memory(self.spec.sim, width, height, fields, name)

    def __call__(self, buffers: SimBuffers | None = None) -> WarehouseSim:
        """A new simulator, optionally writing its state into shared ``buffers``."""
        return WarehouseSim(
            self.spec.sim,
            self.layout,
            self.distance_model,
            self.tasks,
            buffers,
            executor=self.spec.navigator.executor(),
        )


def build_sim(spec: SimSpec) -> WarehouseSim:
    """One simulator for ``spec``."""
    return SimFactory(spec)()


def sim_config(values: SimConfig | Mapping[str, Any]) -> SimConfig:
    """A :class:`SimConfig` from a mapping; an unknown key is an error listing the valid ones."""
    if isinstance(values, SimConfig):
        return values
    allowed = [f.name for f in dataclasses.fields(SimConfig)]
    unknown = sorted(set(values) - set(allowed))
    if unknown:
        raise ConfigError(f"unknown key sim.{unknown[0]}; valid keys: {', '.join(allowed)}")
    return SimConfig(**dict(values))


def _plain(value: Any) -> Any:
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    return value
