"""Navigator options (the ``navigator`` config group): the distance model the policies
observe, and the executor that moves the robots."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType
from typing import ClassVar

from rtaw_marl.errors import ConfigError
from rtaw_marl.sim.distances import DistanceModel, EuclideanDistance, GridDistance
from rtaw_marl.sim.execution import Executor
from rtaw_marl.sim.layout import Layout
from rtaw_marl.sim.mapf import CBSExecutor, SIPPExecutor
from rtaw_marl.sim.mapf.pibt import PIBTExecutor
from rtaw_marl.sim.options.base import Option

__all__ = [
    "NAVIGATORS",
    "AStarConfig",
    "CBSConfig",
    "DirectConfig",
    "NavigatorOption",
    "PIBTConfig",
    "SIPPConfig",
]

_NO_NOISE: Mapping[str, float] = MappingProxyType({"noise_mean": 0.0, "noise_var": 0.0})


@dataclass(kw_only=True)
class NavigatorOption(Option):
    """A navigator option: the distance model the policies observe, and how robots travel
    (independently, or executed collision-free by a path-planning fleet)."""

    group: ClassVar[str] = "navigator"
    #: Whether robots occupy cells and wait for each other.
    collision_aware: ClassVar[bool] = False
    #: Simulator keys this option changes unless they are given (its YAML twin's ``sim``
    #: block): ``SimSpec.of(navigator="sipp")`` and ``navigator=sipp`` build the same.
    sim_defaults: ClassVar[Mapping[str, float]] = MappingProxyType({})

    def distance_model(self, layout: Layout) -> DistanceModel:
        """The distance model on ``layout`` (shared by every simulator of a batch)."""
        return GridDistance(layout)

    def executor(self) -> Executor | None:
        """A fresh executor for one simulator; ``None`` means instant, independent travel."""
        return None


@dataclass(kw_only=True)
class DirectConfig(NavigatorOption):
    """Euclidean distances, obstacles ignored (the paper's "Direct" navigation)."""

    name: str = "direct"

    def distance_model(self, layout: Layout) -> DistanceModel:
        return EuclideanDistance(layout)


@dataclass(kw_only=True)
class AStarConfig(NavigatorOption):
    """True 4-connected shortest paths (cached BFS distance fields).

    Attributes:
        cache_mb: Memory of the distance fields kept (LRU); a field costs
            ``4 (H + 2)(W + 2)`` bytes (280 KB on LoRR's 500 x 140 warehouse_large).
    """

    name: str = "astar"
    cache_mb: float = 256.0

    def __post_init__(self) -> None:
        _check_positive("navigator.cache_mb", self.cache_mb, "number", float)
        super().__post_init__()

    def distance_model(self, layout: Layout) -> DistanceModel:
        return GridDistance(layout, cache_mb=self.cache_mb)


@dataclass(kw_only=True)
class SIPPConfig(NavigatorOption):
    """Collision-aware: prioritized Safe Interval Path Planning on the shared grid; the
    policy observes A* distances.

    Attributes:
        time_limit: Seconds one planning call may take before the run stops with an error.
    """

    name: str = "sipp"
    collision_aware: ClassVar[bool] = True
    # Tasks are timed by their executed paths in whole seconds: no completion noise.
    sim_defaults: ClassVar[Mapping[str, float]] = _NO_NOISE
    time_limit: float = 10.0

    def __post_init__(self) -> None:
        # Before the generic type check: this message says what the key needs.
        _check_positive("navigator.time_limit", self.time_limit, "number", float)
        super().__post_init__()

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
    # Tasks are timed by their executed paths in whole seconds: no completion noise.
    sim_defaults: ClassVar[Mapping[str, float]] = _NO_NOISE
    time_limit: float = 10.0
    max_nodes: int = 200

    def __post_init__(self) -> None:
        # Before the generic type check: these messages say what the keys need.
        _check_positive("navigator.time_limit", self.time_limit, "number", float)
        _check_positive("navigator.max_nodes", self.max_nodes, "integer", int)
        super().__post_init__()

    def executor(self) -> Executor:
        return CBSExecutor(time_limit=self.time_limit, max_nodes=self.max_nodes)


@dataclass(kw_only=True)
class PIBTConfig(NavigatorOption):
    """Collision-aware for any fleet size: lifelong PIBT moves every robot one cell per
    timestep (:mod:`rtaw_marl.sim.mapf.pibt`); the policy observes A* distances. By
    default as LoRR's planner moves its robots: headings and quarter turns, traffic-flow
    guidance (``turns=false guidance=0``: the turn-free model on shortest paths).

    Attributes:
        stall_limit: Timesteps without any robot reaching a goal before the episode
            stops with an error (a deadlock or livelock).
        patience: Timesteps a busy robot may go without getting nearer its goal before
            its priority is drawn at random each timestep (priority rotation); ``null``
            (the default, as LoRR's planner): none, dead ends handled by a priority
            bonus instead. Rotation scatters the queues of a 10,000-robot fleet.
        record: Keep every robot's cell at every timestep, for the conflict checker and
            the renderer (``4 M`` bytes per timestep). ``false``: rtaw-eval's episodes
            are not checked against the schedule (there is none; PIBT itself keeps
            robots on distinct cells), and nothing can render them.
        cache_mb: Memory of the distance fields kept (LRU), shared by the policy's
            queries and the robots' goals: lifelong fleets revisit cells (a robot
            decides at the delivery cell whose field it followed).
        turns: LoRR's action model: robots have headings (all start facing east), move
            forward only, and a quarter turn takes a timestep; a forward move into a
            cell whose robot does not move forward too is cancelled. ``false``: robots
            move to any neighbouring cell without turning (the turn-free model).
        guidance: Traffic-flow guidance: each robot follows a guide path planned on
            edge costs ``1 + guidance x`` the number of other robots' guide paths using
            the edge the other way (contraflow); ``0``: none, shortest paths. With
            ``turns``, the defaults are LoRR's planner: within 5% of LoRR's own counts
            on its random map (docs/lorr.md).
        guide_replans: Guide paths re-planned per timestep besides the ones that must
            be (new goal, robot pushed off its path), oldest first, on the flows as
            they are now: LoRR's planner re-optimises its guide paths this way until
            its deadline. A count, so episodes stay deterministic; ``0``: none.
    """

    name: str = "pibt"
    collision_aware: ClassVar[bool] = True
    # Tasks are timed by the executed moves in whole seconds: no completion noise.
    sim_defaults: ClassVar[Mapping[str, float]] = _NO_NOISE
    stall_limit: int = 10_000
    patience: int | None = None
    record: bool = True
    cache_mb: float = 1024.0
    turns: bool = True
    guidance: float = 1.0
    guide_replans: int = 0

    def __post_init__(self) -> None:
        g = self.guidance
        if isinstance(g, bool) or not isinstance(g, (int, float)) or not 0 <= g < float("inf"):
            raise ConfigError(f"navigator.guidance must be a number >= 0, got {g!r}")
        _check_positive("navigator.stall_limit", self.stall_limit, "integer", int)
        if self.patience is not None:
            _check_positive("navigator.patience", self.patience, "integer", int)
        _check_positive("navigator.cache_mb", self.cache_mb, "number", float)
        r = self.guide_replans
        if isinstance(r, bool) or not isinstance(r, int) or r < 0:
            raise ConfigError(f"navigator.guide_replans must be an integer >= 0, got {r!r}")
        super().__post_init__()

    def distance_model(self, layout: Layout) -> DistanceModel:
        return GridDistance(layout, cache_mb=self.cache_mb)

    def executor(self) -> Executor:
        return PIBTExecutor(
            stall_limit=self.stall_limit, patience=self.patience, record=self.record,
            turns=self.turns, guidance=float(self.guidance), guide_replans=self.guide_replans,
        )  # fmt: skip


def _check_positive(key: str, value: object, what: str, kind: type) -> None:
    numeric = (int,) if kind is int else (int, float)
    ok = isinstance(value, numeric) and not isinstance(value, bool)
    if not ok or not 0 < value < float("inf"):  # type: ignore[operator]
        raise ConfigError(f"{key} must be a positive {what}, got {value!r}")


NAVIGATORS: dict[str, type[NavigatorOption]] = {
    cls.__dataclass_fields__["name"].default: cls
    for cls in (DirectConfig, AStarConfig, SIPPConfig, CBSConfig, PIBTConfig)
}
