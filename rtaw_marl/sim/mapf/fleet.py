"""Robots executing their tasks on the grid without collisions: the shared machinery.

A :class:`Fleet` owns, for one episode, where every robot is at every integer time
(its *timeline*) and the goals (*legs*) it still has to reach. Its executor
(:mod:`rtaw_marl.sim.mapf.executors`) calls :meth:`Fleet.assign` when the simulator
gives a task to a free robot; the fleet plans the robot's way to the task's origin and
on to its destination and records the planned pickup and delivery times; the robot is
free again at the delivery.

Execution model (discrete time, 1 s per step): a robot moves to a 4-connected
neighbour or waits; two robots never share a cell nor swap cells; a robot that has
reached its last goal holds that cell until it gets a new task.

Blocking. A robot's goal can be held by another robot, or a corridor can be closed by
robots standing in it. A robot that cannot plan is *deferred*: it waits where it is
(holding its cell) and is retried whenever another robot commits a new trajectory,
because only then do holds change. When a deferred robot is blocked by robots that
will not move by themselves (deferred or, once the last task is assigned, idle), those
are moved off its way (:mod:`rtaw_marl.sim.mapf.evacuation`). A fleet that still
cannot move raises :class:`~rtaw_marl.errors.PlanningError`, never hangs.

The planning strategy is a subclass (:mod:`rtaw_marl.sim.mapf.strategies`):
:class:`~rtaw_marl.sim.mapf.strategies.SIPPFleet` or
:class:`~rtaw_marl.sim.mapf.strategies.CBSFleet`.
"""

from __future__ import annotations

import time
from abc import ABC, abstractmethod
from dataclasses import dataclass

import numpy as np

from rtaw_marl.errors import PlanningError, PlanningTimeout
from rtaw_marl.sim.mapf.cbs import CBSStats, cbs_solve
from rtaw_marl.sim.mapf.evacuation import parking_cells, route_cells, taken_cells
from rtaw_marl.sim.mapf.grid import Grid
from rtaw_marl.sim.mapf.reservations import ReservationTable
from rtaw_marl.sim.mapf.sipp import sipp_plan

__all__ = ["DELIVER", "EXPANSIONS_PER_NODE", "PARK", "PICKUP", "Fleet", "Leg"]

PICKUP, DELIVER, PARK = 0, 1, 2
#: Low-level A* expansions a CBS call may spend per high-level node of its budget: a
#: few hard low-level searches (a goal cut off under many constraints) would otherwise
#: exhaust the time limit within the node budget.
EXPANSIONS_PER_NODE = 1000
_KINDS = ("pickup", "delivery", "parking")


@dataclass
class Leg:
    """A goal of a robot: a task's origin or destination, or a parking cell."""

    cell: int
    task: int
    kind: int
    time: int | None = None  # planned arrival; None while not planned


class Fleet(ABC):
    """Collision-free execution of assigned tasks; subclasses choose the planner.

    Args:
        grid: The grid the robots move on.
        num_robots: ``M``.
        time_limit: Seconds one planning call may take.
        max_nodes: High-level node budget of a joint CBS call.

    Public state after :meth:`reset`:
        timeline: Per robot, its cell at every time ``0 .. T_m`` planned so far.
        legs: Per robot, its goals (planned and not yet planned).
        free_at: ``float64 [M]`` time each robot is free, ``inf`` while deferred.
        estimated_free_at: ``float64 [M]`` the same with single-robot estimates for
            deferred robots (what the policy observes).
        task_pickup, task_delivered: ``int64 [K]`` planned times per task, ``-1``
            while not planned.
        planning_calls, evacuations, cbs_calls, fallbacks: Counters of the episode.
    """

    name = ""

    def __init__(self, grid: Grid, num_robots: int, time_limit: float, max_nodes: int) -> None:
        self.grid = grid
        self.num_robots = num_robots
        self.time_limit = time_limit
        self.max_nodes = max_nodes
        self.free_at = np.zeros(num_robots, dtype=np.float64)
        self.estimated_free_at = np.zeros(num_robots, dtype=np.float64)
        self.last_cbs = CBSStats()

    # ------------------------------------------------------------------ episode
    def reset(self, starts: np.ndarray, free_at: np.ndarray, num_tasks: int) -> None:
        """Robots at ``starts [M, 2]`` (x, y), first free at integer times ``free_at [M]``."""
        self.timeline: list[list[int]] = [[c] for c in self.grid.cells(starts).tolist()]
        self.legs: list[list[Leg]] = [[] for _ in range(self.num_robots)]
        self.free_at[:] = free_at
        self.estimated_free_at[:] = free_at
        self.task_pickup = np.full(num_tasks, -1, dtype=np.int64)
        self.task_delivered = np.full(num_tasks, -1, dtype=np.int64)
        self.closing = False
        self._budget = 2 * self.num_robots  # evacuations allowed per assignment
        self.planning_calls = 0
        self.evacuations = 0
        self.cbs_calls = 0
        self.fallbacks = 0  # CBS calls past their budget, planned by SIPP instead
        self._waiting: set[int] = set()  # robots with unplanned legs (kept by _refresh)

    def assign(self, robot: int, now: int, task: int, origin: tuple[int, int],
               destination: tuple[int, int]) -> None:  # fmt: skip
        """Give ``task`` (``origin`` -> ``destination``, as ``(x, y)``) to ``robot``
        (free at ``now``), plan it, and retry deferred robots."""
        o, d = self.grid.cell(*origin), self.grid.cell(*destination)
        self.legs[robot] = [leg for leg in self.legs[robot] if leg.time is None or leg.time > now]
        self.legs[robot] += [Leg(o, task, PICKUP), Leg(d, task, DELIVER)]
        self._budget = 2 * self.num_robots
        self._serve(robot, now)
        self._retry(now)

    def finish(self, now: int) -> None:
        """Complete every assigned task; idle robots may now be moved out of the way.

        Raises:
            PlanningError: Some robots stay blocked.
        """
        self.closing = True
        self._budget = 4 * self.num_robots
        self._retry(now, force=True)  # idle robots can be moved aside from now on
        if self.deferred():
            self.resolve(now)

    def resolve(self, now: int) -> None:
        """Unblock deferred robots once every robot has stopped moving (no robot is free).

        Raises:
            PlanningError: No deferred robot can move even then.
        """
        while self.deferred():
            later = max(now, max(len(t) - 1 for t in self.timeline))
            before = sum(len(t) for t in self.timeline), len(self.deferred())
            self._retry(later, force=True)
            stuck = (sum(len(t) for t in self.timeline), len(self.deferred())) == before
            if stuck and not self._rescue(later):
                raise PlanningError(self._blocked_message(later))
            if not self.closing:
                return

    def stats(self) -> dict[str, float]:
        """Counters of the episode: planning calls, evacuations, CBS fallbacks."""
        return {
            "planning_calls": float(self.planning_calls),
            "evacuations": float(self.evacuations),
            "cbs_fallbacks": float(self.fallbacks),
        }

    def deferred(self) -> list[int]:
        """Robots with legs not yet planned, by id."""
        return sorted(self._waiting)

    def positions(self) -> np.ndarray:
        """``int64 [T + 1, M, 2]`` cell ``(x, y)`` of every robot at every time."""
        horizon = max(len(t) for t in self.timeline)
        flat = np.array([t + [t[-1]] * (horizon - len(t)) for t in self.timeline]).T
        return self.grid.xys(flat).astype(np.int64)

    # ------------------------------------------------------------------ strategy hooks
    @abstractmethod
    def _plan(
        self, robot: int, now: int, legs: list[Leg], blockers: set[int] | None = None
    ) -> bool:
        """Plan ``robot`` through ``legs`` (and commit) or return False.

        ``blockers`` receives the held cells that made the plan fail, when known.
        """

    def _attempts(self, pending: list[Leg]) -> list[list[Leg]]:
        """The leg lists :meth:`_serve` tries to plan, in order (all pending legs)."""
        return [pending]

    def _may_retry(self, robot: int, now: int, force: bool) -> bool:
        """Whether :meth:`_retry` re-plans deferred ``robot`` now: once it stands still."""
        del force
        return self._end(robot) <= now

    def _on_serve(self, robot: int) -> None:
        """Called when ``robot`` is about to be (re-)planned."""
        del robot

    def _on_blocked(self, robot: int, blockers: set[int]) -> None:
        """Called when ``robot`` stays deferred; ``blockers`` made its search fail."""
        del robot, blockers

    def _on_released(self, cell: int) -> None:
        """Called when a robot leaves ``cell``, which it held forever until now."""
        del cell

    def _rescue(self, now: int) -> bool:
        """Last resort before reporting a deadlock; True when some robot moved."""
        del now
        return False

    # ------------------------------------------------------------------ serving
    def _serve(self, robot: int, now: int) -> bool:
        """Plan ``robot``'s pending legs, moving robots out of its way once if needed."""
        tries = self._attempts(self._pending(robot))
        blockers: set[int] = set()
        self._on_serve(robot)
        for attempt in range(2):
            if any(self._plan(robot, now, legs, blockers) for legs in tries):
                self._refresh(robot, now)
                return True
            if attempt == 0 and not self._evacuate_for(robot, now):
                break
        self._on_blocked(robot, blockers)
        self._refresh(robot, now)
        return False

    def _retry(self, now: int, force: bool = False) -> None:
        """Re-plan deferred robots until none makes progress."""
        progress = True
        while progress:
            progress = False
            for robot in self.deferred():
                if self._may_retry(robot, now, force):
                    progress |= self._serve(robot, now)

    def _evacuate_for(self, robot: int, now: int) -> bool:
        """Move robots that will not move by themselves off ``robot``'s way.

        First off one shortest route through its pending legs; if nobody on it can be
        moved, off every shortest route (a robot trapped in a pocket on one route may
        leave room on another).
        """
        return any(self._evacuate_from(robot, now, self._route(robot, wide)) for wide in (0, 1))

    def _evacuate_from(self, robot: int, now: int, route: set[int]) -> bool:
        """Send every stuck robot on ``route`` to the nearest parking cell it can reach."""
        if self._budget <= 0:
            return False
        stuck = [
            k for k in range(self.num_robots)
            if k != robot and self._end(k) <= now and self.timeline[k][-1] in route
            and (self._pending(k) or self.closing)
        ]  # fmt: skip
        moved = False
        for k in stuck:
            for cell in parking_cells(self.grid, self.timeline[k][-1], route | self._taken()):
                leg = Leg(cell, -1, PARK)
                pending = self._pending(k)
                self.legs[k] = [g for g in self.legs[k] if g.time is not None] + [leg]
                ok = self._plan(k, now, [leg])
                self.legs[k] += pending
                if ok:
                    self._budget -= 1
                    self.evacuations += 1
                    self._refresh(k, now)
                    moved = True
                    break
                self.legs[k].remove(leg)
        return moved

    def _route(self, robot: int, wide: bool = False) -> set[int]:
        """Cells of ``robot``'s shortest route(s) through its pending legs."""
        goals = [leg.cell for leg in self._pending(robot)]
        return route_cells(self.grid, self.timeline[robot][-1], goals, bool(wide))

    def _taken(self) -> set[int]:
        """Where robots end up and every robot's goals: no parking there."""
        ends = (t[-1] for t in self.timeline)
        return taken_cells(ends, ([leg.cell for leg in legs] for legs in self.legs))

    # ------------------------------------------------------------------ planners
    def _plan_around(
        self,
        table: ReservationTable,
        robot: int,
        t0: int,
        legs: list[Leg],
        blockers: set[int] | None = None,
    ) -> bool:
        """SIPP for ``robot`` from its cell at ``t0`` around the reservations of ``table``."""
        start = self.timeline[robot][-1] if t0 >= self._end(robot) else self.timeline[robot][t0]
        table.release_from(robot, t0)
        goals = [leg.cell for leg in legs]
        try:
            found = sipp_plan(self.grid, table, start, t0, goals, self._deadline(), blockers)
        except PlanningTimeout as exc:
            raise self._timeout(exc, [robot], t0) from None
        if found is None:
            table.reserve(robot, t0, [start])
            return False
        cells, times = found
        table.reserve(robot, t0, cells)
        self._commit(robot, t0, cells, legs, times)
        # The robot's old cell is no longer held forever.
        self._on_released(start)
        return True

    def _joint(self, agents: list[int], agent_legs: list[list[Leg]], now: int) -> bool:
        """One CBS call: ``agents`` through their legs from ``now``, the rest standing still."""
        blocked = [self.timeline[r][-1] for r in range(self.num_robots) if r not in agents]
        starts = [self._at(r, now) for r in agents]
        goals = [[g.cell for g in gl] for gl in agent_legs]
        try:
            self.cbs_calls += 1
            sol = cbs_solve(self.grid, starts, goals, self._deadline(), blocked=blocked,
                            max_nodes=self.max_nodes,
                            max_expansions=EXPANSIONS_PER_NODE * self.max_nodes,
                            stats=self.last_cbs)  # fmt: skip
        except PlanningTimeout as exc:
            raise self._timeout(exc, agents, now) from None
        if sol is None:
            return False
        for r, gl, path, times in zip(agents, agent_legs, sol.paths, sol.goal_times, strict=True):
            self._commit(r, now, path.tolist(), gl, [now + int(t) for t in times])
            self._refresh(r, now)
        return True

    # ------------------------------------------------------------------ bookkeeping
    def _at(self, robot: int, t: int) -> int:
        line = self.timeline[robot]
        return line[min(t, len(line) - 1)]

    def _pending(self, robot: int) -> list[Leg]:
        return [leg for leg in self.legs[robot] if leg.time is None]

    def _end(self, robot: int) -> int:
        return len(self.timeline[robot]) - 1

    def _deadline(self) -> float:
        self.planning_calls += 1
        return time.perf_counter() + self.time_limit

    def _timeout(self, exc: PlanningTimeout, robots: list[int], now: int) -> PlanningTimeout:
        return PlanningTimeout(
            f"navigator {self.name}: planning robot(s) {robots} at t={now} ran past "
            f"navigator.time_limit={self.time_limit:g} s ({exc})"
        )

    def _commit(self, robot: int, t0: int, cells: list[int], legs: list[Leg],
                goal_times: list[int]) -> None:  # fmt: skip
        """Replace ``robot``'s timeline from ``t0`` by ``cells``; record the goal times."""
        line = self.timeline[robot]
        del line[t0 + 1 :]
        line.extend([line[-1]] * (t0 + 1 - len(line)))
        line.extend(cells[1:])
        for leg, t in zip(legs, goal_times, strict=True):
            leg.time = int(t)
            if leg.kind == PICKUP:
                self.task_pickup[leg.task] = t
            elif leg.kind == DELIVER:
                self.task_delivered[leg.task] = t

    def _refresh(self, robot: int, now: int) -> None:
        """Update ``robot``'s free times (estimated by distances while it is deferred)."""
        pending = self._pending(robot)
        end = self._end(robot)
        last = next((g for g in reversed(self.legs[robot]) if g.kind != PARK), None)
        if pending:
            self._waiting.add(robot)
        else:
            self._waiting.discard(robot)
            free = last.time if last is not None and last.time is not None else end
            self.free_at[robot] = self.estimated_free_at[robot] = max(free, 0)
            return
        self.free_at[robot] = np.inf
        here, total = self.timeline[robot][-1], 0.0
        for leg in pending:
            total += float(self.grid.distance(here, leg.cell))
            here = leg.cell
        self.estimated_free_at[robot] = max(now, end) + total

    def _blocked_message(self, now: int) -> str:
        parts = []
        for r in self.deferred()[:5]:
            leg = self._pending(r)[0]
            x, y = self.grid.xy(leg.cell)
            at = self.grid.xy(self.timeline[r][-1])
            parts.append(
                f"robot {r} at (x={at[0]}, y={at[1]}) cannot reach the {_KINDS[leg.kind]} "
                f"cell (x={x}, y={y}) of task {leg.task}"
            )
        return (
            f"navigator {self.name}: the robots are deadlocked at t={now}: "
            + "; ".join(parts)
            + " (robots hold their cells and none of those in the way could be moved aside)"
        )
