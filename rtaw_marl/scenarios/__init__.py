"""Named scenarios: one place that defines each setting the project trains and reports on.

A :class:`Scenario` is a simulator spec (the ``sim``, ``layout``, ``navigator`` and
``tasks`` groups, as names and mappings) plus its evaluation settings: the evaluation
seeds and the shipped learned policies that belong to it. The same name works everywhere:

* Python: ``SCENARIOS["C_astar_m10"].spec()``, ``scenario("C_astar_m10")``,
  ``warehouse_v1.env(scenario="C_astar_m10")``;
* the command line: ``rtaw-eval scenario=C_astar_m10`` and ``rtaw-train
  scenario=C_astar_m10``, and ``rtaw-eval row=C`` (a Table I row: the scenario and its
  shipped policies): options that :mod:`rtaw_marl.config.scenarios` stores in Hydra's
  ConfigStore straight from this registry (no YAML file);
* LoRR 2024 problem files: ``lorr_scenario(path)`` and ``rtaw-eval scenario=lorr
  tasks.problem=PATH`` (:mod:`rtaw_marl.scenarios.lorr`);
* the benchmarks project beside the package (`benchmarks/studies.py`), whose studies
  produce docs/results.md.

``tests/scenarios/test_scenarios.py`` checks that Hydra and Python build the same
simulator for every name.
This package is plain Python over :mod:`rtaw_marl.sim` (no torch, no Hydra).
"""

from __future__ import annotations

from rtaw_marl.scenarios.lorr import lorr_scenario
from rtaw_marl.scenarios.registry import (
    EVAL_SEEDS,
    ROWS,
    SCENARIOS,
    TABLE1_ROBOTS,
    Scenario,
    scenario,
)

__all__ = [
    "EVAL_SEEDS",
    "ROWS",
    "SCENARIOS",
    "TABLE1_ROBOTS",
    "Scenario",
    "lorr_scenario",
    "scenario",
]
