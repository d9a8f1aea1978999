"""Collision-aware navigators: ``sipp`` and ``cbs``.

Both answer distance queries as :class:`~rtaw_marl.sim.navigation.AStarNavigator`
does (the single-robot shortest paths a policy observes, as in the paper, which
trains with A* and tests with SIPP and CBS), and execute every episode on a shared
grid through a :class:`~rtaw_marl.sim.fleet.Fleet`: robots wait for each other, and
a task's TTD is the real arrival time at its origin, waits included.

``sipp``
    Prioritized planning: each newly assigned robot runs Safe Interval Path Planning
    around the trajectories of all robots planned before it and the cells where
    robots stand.
``cbs``
    Conflict-Based Search over all moving robots, re-planned from the current time
    whenever a robot gets a new task (full re-planning, not windowed: trajectories are
    short, so a whole-path solution costs little and is conflict-free as executed,
    without extra re-planning events). A call that needs more than ``max_nodes``
    high-level nodes falls back to planning the new robot alone around the others.

Completion times come from the planned paths and are whole seconds, so the
simulator's completion noise must be zero (``env.noise_mean=0 env.noise_var=0``; the
``navigator=sipp``/``navigator=cbs`` config options set it).
"""

from __future__ import annotations

from rtaw_marl.errors import ConfigError
from rtaw_marl.sim.fleet import CBSFleet, Fleet, SIPPFleet
from rtaw_marl.sim.layout import Layout
from rtaw_marl.sim.navigation import AStarNavigator

__all__ = ["CBSNavigator", "SIPPNavigator"]


class SIPPNavigator(AStarNavigator):
    """A* distances; episodes executed by prioritized SIPP planning.

    Args:
        layout: The grid.
        time_limit: Seconds one planning call may take before
            :class:`~rtaw_marl.errors.PlanningTimeout` is raised.
        cache_mb: Memory budget of the distance-field cache.
    """

    name = "sipp"

    def __init__(self, layout: Layout, time_limit: float = 10.0, cache_mb: float = 256.0) -> None:
        super().__init__(layout, cache_mb=cache_mb)
        if isinstance(time_limit, bool) or not (
            isinstance(time_limit, (int, float)) and time_limit > 0
        ):
            raise ConfigError(f"navigator.time_limit must be a positive number, got {time_limit!r}")
        self.time_limit = float(time_limit)

    def make_fleet(self, num_robots: int) -> Fleet:
        return SIPPFleet(self, num_robots, self.time_limit)


class CBSNavigator(SIPPNavigator):
    """A* distances; episodes executed by Conflict-Based Search over the moving robots.

    Args:
        layout: The grid.
        time_limit: Seconds one planning call may take.
        max_nodes: High-level CBS nodes per call; past it the newly assigned robot plans
            alone around the others' paths (counted in ``Fleet.fallbacks``).
        cache_mb: Memory budget of the distance-field cache.
    """

    name = "cbs"

    def __init__(
        self,
        layout: Layout,
        time_limit: float = 10.0,
        max_nodes: int = 200,
        cache_mb: float = 256.0,
    ) -> None:
        super().__init__(layout, time_limit=time_limit, cache_mb=cache_mb)
        if isinstance(max_nodes, bool) or not isinstance(max_nodes, int) or max_nodes < 1:
            raise ConfigError(f"navigator.max_nodes must be a positive integer, got {max_nodes!r}")
        self.max_nodes = max_nodes

    def make_fleet(self, num_robots: int) -> Fleet:
        return CBSFleet(self, num_robots, self.time_limit, self.max_nodes)
