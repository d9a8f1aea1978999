"""Multi-robot path finding: collision-aware execution of the simulator's tasks.

Layers, bottom up (each module imports only from those above it in this list, and
from :mod:`rtaw_marl.sim`'s layout, BFS kernel and execution interface):

* :mod:`~rtaw_marl.sim.mapf.grid`: :class:`Grid`, the one cell encoding and distance fields;
* :mod:`~rtaw_marl.sim.mapf.reservations`: who occupies which cell when;
* :mod:`~rtaw_marl.sim.mapf.sipp`: Safe Interval Path Planning for one robot;
* :mod:`~rtaw_marl.sim.mapf.cbs` (with :mod:`~rtaw_marl.sim.mapf.cbs_low`):
  Conflict-Based Search;
* :mod:`~rtaw_marl.sim.mapf.fleet`, :mod:`~rtaw_marl.sim.mapf.evacuation`,
  :mod:`~rtaw_marl.sim.mapf.strategies`: a fleet of robots executing tasks
  (:class:`SIPPFleet`, :class:`CBSFleet`);
* :mod:`~rtaw_marl.sim.mapf.executors`: :class:`SIPPExecutor` and
  :class:`CBSExecutor`, the simulator's collision-aware
  :class:`~rtaw_marl.sim.execution.Executor`;
* :mod:`~rtaw_marl.sim.mapf.schedule` and :mod:`~rtaw_marl.sim.mapf.conflicts`: the
  executed episode and its independent checker (which shares no code with the planners).
"""

from __future__ import annotations

from rtaw_marl.sim.mapf.cbs import CBSSolution, CBSStats, cbs_solve
from rtaw_marl.sim.mapf.conflicts import check_schedule, find_violations
from rtaw_marl.sim.mapf.executors import CBSExecutor, FleetExecutor, SIPPExecutor
from rtaw_marl.sim.mapf.fleet import Fleet
from rtaw_marl.sim.mapf.grid import Grid
from rtaw_marl.sim.mapf.reservations import ReservationTable
from rtaw_marl.sim.mapf.schedule import Schedule
from rtaw_marl.sim.mapf.sipp import sipp_plan
from rtaw_marl.sim.mapf.strategies import CBSFleet, SIPPFleet

__all__ = [
    "CBSExecutor",
    "CBSFleet",
    "CBSSolution",
    "CBSStats",
    "Fleet",
    "FleetExecutor",
    "Grid",
    "ReservationTable",
    "SIPPExecutor",
    "SIPPFleet",
    "Schedule",
    "cbs_solve",
    "check_schedule",
    "find_violations",
    "sipp_plan",
]
