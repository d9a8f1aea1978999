"""``scenario=NAME`` and ``row=NAME``: the scenario registry's entries as Hydra options.

Each :data:`~rtaw_marl.scenarios.SCENARIOS` entry is stored in Hydra's ConfigStore as
option ``NAME`` of the ``scenario`` group, each Table I row of
:data:`~rtaw_marl.scenarios.ROWS` as option ``ROW`` of the ``row`` group, straight from
the registry: no YAML file is written, so none can drift from it. A node is what its
YAML file would hold, package ``_global_``:

* a scenario's ``defaults`` list overrides the ``layout``, ``navigator`` and ``tasks``
  groups with its options (``override /layout: C``), and its ``sim``, ``layout``,
  ``navigator`` and ``tasks`` sections set the keys it changes besides;
  ``scenario=default`` sets nothing: each command's own defaults are the default
  scenario (``rtaw-render`` keeps its SIPP execution; the tests check that ``rtaw-eval``
  and ``rtaw-train`` then build ``SCENARIOS["default"]``);
* a row overrides the ``scenario`` group with its scenario and sets ``pretrained`` to
  the scenario's shipped policies (``RTAW+`` first);
* ``scenario=lorr`` takes a League of Robot Runners 2024 problem from
  ``tasks.problem=FILE.json`` (:mod:`rtaw_marl.scenarios.lorr`): its map, tasks and
  start cells, the robots, reveal window and task count derived from the problem by the
  ``${lorr:...}`` resolver, PIBT execution for LoRR's 5,000 timesteps.
"""

from __future__ import annotations

from typing import Any

from hydra.core.config_store import ConfigStore

from rtaw_marl.scenarios import ROWS, SCENARIOS, Scenario
from rtaw_marl.sim.lorr import LORR_SIM

__all__ = ["LORR", "SIM_GROUPS", "lorr_node", "register_scenarios", "row_node", "scenario_node"]

#: The option groups a scenario chooses (its ``sim`` keys are values, not a choice).
SIM_GROUPS = ("layout", "navigator", "tasks")
#: The ``scenario`` option of a LoRR problem file.
LORR = "lorr"


def scenario_node(s: Scenario) -> dict[str, Any]:
    """The ``scenario=<name>`` option: its group choices and the keys it sets."""
    if s.name == "default":
        return {}
    defaults: list[Any] = []
    sections: dict[str, Any] = {}
    for group in SIM_GROUPS:
        name, keys = s.choice(group)
        defaults.append({f"override /{group}": name})
        if keys:
            sections[group] = keys
    sim = {"sim": dict(s.sim)} if s.sim else {}
    return {"defaults": defaults, **sim, **sections}


def row_node(row: str) -> dict[str, Any]:
    """The ``row=<row>`` option: a Table I row's scenario and its shipped policies."""
    s = SCENARIOS[ROWS[row]]
    return {
        "defaults": [{"override /scenario": s.name}],
        "pretrained": list(s.policies.values()),
    }


def lorr_node() -> dict[str, Any]:
    """The ``scenario=lorr`` option: a LoRR problem named by ``tasks.problem``."""
    sim = {
        "num_robots": "${lorr:num_robots,${tasks.problem}}",
        "queue_len": "${lorr:queue_len,${tasks.problem},${sim.num_robots}}",
        "num_tasks": "${lorr:num_tasks,${tasks.problem},${sim.num_robots},${sim.horizon}}",
        **LORR_SIM,
    }
    return {
        "defaults": [
            {"override /layout": "lorr"},
            {"override /navigator": "pibt"},
            {"override /tasks": "lorr"},
        ],
        "sim": sim,
        "layout": {"problem": "${tasks.problem}"},
    }


def register_scenarios(store: ConfigStore) -> None:
    """Store every scenario, ``scenario=lorr`` and every Table I row in ``store``."""
    for name, s in SCENARIOS.items():
        store.store(group="scenario", name=name, node=scenario_node(s), package="_global_")
    store.store(group="scenario", name=LORR, node=lorr_node(), package="_global_")
    for row in ROWS:
        store.store(group="row", name=row, node=row_node(row), package="_global_")
