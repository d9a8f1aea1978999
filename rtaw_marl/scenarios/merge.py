"""A named scenario with a user's own overrides: one rule for every env adapter.

``warehouse_v1.env(scenario="C_astar_m10", num_robots=30)`` and
``gymnasium.make("rtaw/warehouse-single-v1", scenario="C_astar_m10", num_robots=30)``
build the same simulator: the groups given override the scenario's, and the simulator
keys given override its ``sim`` keys one by one.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from rtaw_marl.scenarios.registry import Scenario, scenario
from rtaw_marl.sim.builder import SimSpec

__all__ = ["spec_with"]


def spec_with(
    named: str | Scenario | None,
    sim: Mapping[str, Any],
    layout: Any = None,
    navigator: Any = None,
    tasks: Any = None,
) -> SimSpec:
    """The simulator spec of ``named`` (a scenario name, a scenario, or None for the
    defaults) with the given groups and keys on top.

    Raises:
        ConfigError: An unknown scenario name (the message lists them), option or key.
    """
    if named is not None:
        base = named if isinstance(named, Scenario) else scenario(named)
        layout = base.layout if layout is None else layout
        navigator = base.navigator if navigator is None else navigator
        tasks = base.tasks if tasks is None else tasks
        sim = {**base.sim, **sim}
    return SimSpec.of(sim, layout, navigator, tasks)
