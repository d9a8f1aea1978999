"""League of Robot Runners 2024 problems as scenarios: ``lorr_scenario(path)`` in Python,
``scenario=lorr tasks.problem=PATH`` on the command line (the ``scenario`` option
:func:`rtaw_marl.config.scenarios.lorr_node`, whose keys the ``${lorr:...}`` resolver,
:func:`lorr_value`, derives from the problem).

Both take the problem's map, tasks and start cells, LoRR's reveal window as the queue
(``sim.queue_len = ceil(numTasksReveal x M)``, ``sim.refill=finish``), LoRR's
5,000-timestep horizon and collision-free PIBT execution; ``sim.num_robots`` defaults
to the problem's ``teamSize`` and the window follows it when it is changed. The values
come from :func:`rtaw_marl.sim.lorr.lorr_sim` on both paths.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

from rtaw_marl.errors import ConfigError
from rtaw_marl.scenarios.registry import Scenario
from rtaw_marl.sim.lorr import LORR_SIM, LoRRProblem, lorr_sim, read_problem

__all__ = ["lorr_scenario", "lorr_value"]


def lorr_scenario(
    problem: str | Path | LoRRProblem,
    num_robots: int | None = None,
    starts: str = "file",
    navigator: str | Mapping[str, Any] = "pibt",
    **sim: object,
) -> Scenario:
    """A LoRR problem as a :class:`~rtaw_marl.scenarios.Scenario`.

    Args:
        problem: The problem JSON (or one read by :func:`~rtaw_marl.sim.lorr.read_problem`).
        num_robots: Robots (default: the problem's ``teamSize``).
        starts: ``file`` or ``random`` start cells (``tasks.starts``).
        navigator: The navigator (``pibt`` executes collision-free at any fleet size).
        **sim: Further simulator keys (``horizon=1000``), checked by
            :class:`~rtaw_marl.sim.config.SimConfig`. ``reassign`` (LoRR's
            reassignment) defaults to whether the navigator is ``pibt``, the one that
            can take a task from a robot on its way.
    """
    if not isinstance(problem, LoRRProblem):
        problem = read_problem(problem)
    horizon = int(sim.pop("horizon", LORR_SIM["horizon"]))  # type: ignore[call-overload]
    keys = {**lorr_sim(problem, num_robots, horizon), **sim}
    name_of = navigator if isinstance(navigator, str) else navigator.get("name")
    if "reassign" not in sim:
        keys["reassign"] = name_of == "pibt"
    name = f"lorr_{problem.path.stem}"
    return Scenario(
        name=name,
        title=f"LoRR {problem.path.stem}, M={keys['num_robots']}",
        description=f"LoRR 2024 problem {problem.path.name}",
        layout={"name": "lorr", "problem": str(problem.path)},
        navigator=navigator,
        tasks={"name": "lorr", "problem": str(problem.path), "starts": starts},
        sim=keys,
    )


def lorr_value(
    key: str, problem: str | None, num_robots: int | None = None, horizon: int | None = None
) -> int:
    """One derived key of a problem (the ``${lorr:KEY,PROBLEM,M,T}`` resolver)."""
    if problem is None or problem == "None":
        raise ConfigError("scenario=lorr needs tasks.problem=FILE.json (a LoRR 2024 problem)")
    robots = None if num_robots is None else int(num_robots)
    t = LORR_SIM["horizon"] if horizon is None else int(horizon)
    return int(lorr_sim(read_problem(problem), robots, t)[key])
