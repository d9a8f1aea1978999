"""Robots executing their tasks on the grid without collisions (the ``sipp``/``cbs`` model).

A :class:`Fleet` owns, for one episode, where every robot is at every integer time
(its *timeline*) and the goals (*legs*) it still has to reach. The simulator's
event-driven loop calls :meth:`Fleet.assign` when it gives a task to a free robot;
the fleet plans the robot's way to the task's origin and on to its destination and
reports the planned delivery time, which is when the robot is free again.

Execution model (discrete time, 1 s per step): a robot moves to a 4-connected
neighbour or waits; two robots never share a cell nor swap cells; a robot that has
reached its last goal holds that cell until it gets a new task.

Blocking. A robot's goal can be held by another robot, or a corridor can be closed by
robots standing in it. A robot that cannot plan is *deferred*: it waits where it is
(holding its cell) and is retried whenever another robot commits a new trajectory,
because only then do holds change. With SIPP a robot that can reach its origin but not
its destination goes to the origin and is deferred there. When a deferred robot is
blocked by robots that will not move by themselves (deferred or, once the last task
is assigned, idle), those are moved off its way: each goes to the nearest cell that is
off the blocked robot's shortest route and is nobody's goal or parking cell. A fleet
that still cannot move raises :class:`~rtaw_marl.errors.PlanningError`, never hangs.

Strategies: :class:`SIPPFleet` (prioritized planning: each newly assigned robot plans
around all earlier trajectories, which never change) and :class:`CBSFleet`
(Conflict-Based Search over every moving robot at each assignment: trajectories are
re-planned jointly from the current time, the past never changes). CBS is exponential
in the number of conflicts and narrow aisles make some joint problems very hard, so a
CBS call has a budget of high-level nodes (and of low-level expansions, 1000 per node);
past it (or when no joint plan exists) the new robot plans alone around the others'
current paths, as SIPP would, and :attr:`CBSFleet.fallbacks` counts how often.
"""

from __future__ import annotations

import time
from abc import ABC, abstractmethod
from collections import deque
from dataclasses import dataclass

import numpy as np

from rtaw_marl.errors import PlanningError, PlanningTimeout
from rtaw_marl.sim.cbs import cbs_solve
from rtaw_marl.sim.navigation import AStarNavigator
from rtaw_marl.sim.reservations import ReservationTable
from rtaw_marl.sim.sipp import sipp_plan

__all__ = ["CBSFleet", "Fleet", "SIPPFleet"]

PICKUP, DELIVER, PARK = 0, 1, 2
#: Low-level A* expansions a CBS call may spend per high-level node of its budget: a
#: few hard low-level searches (a goal cut off under many constraints) would otherwise
#: exhaust the time limit within the node budget.
EXPANSIONS_PER_NODE = 1000
#: High-level node budget of a CBS call (``navigator.max_nodes`` for ``cbs``).
DEFAULT_MAX_NODES = 200
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
        navigator: Single-robot distances and paths on the layout (heuristics).
        num_robots: ``M``.
        time_limit: Seconds one planning call may take.
    """

    name = ""

    def __init__(self, navigator: AStarNavigator, num_robots: int, time_limit: float) -> None:
        self.nav = navigator
        self.num_robots = num_robots
        self.time_limit = time_limit
        self._wp = navigator._wp
        self._free = navigator._free_padded.tolist()
        self._grid_free = ~navigator.layout.obstacles
        self._shape = (navigator.layout.height + 2, navigator.layout.width + 2)
        self.max_nodes = DEFAULT_MAX_NODES
        self.free_at = np.zeros(num_robots, dtype=np.float64)
        self.estimated_free_at = np.zeros(num_robots, dtype=np.float64)

    # ------------------------------------------------------------------ episode
    def reset(self, starts: np.ndarray, free_at: np.ndarray, num_tasks: int) -> None:
        """Robots at ``starts [M, 2]``, first free at integer times ``free_at [M]``."""
        cells = self.nav._padded_index(starts).tolist()
        self.timeline: list[list[int]] = [[c] for c in cells]
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
        # Deferred robot -> held cells that blocked its last search (SIPP), and the
        # deferred robots to retry because one of those cells was released since.
        self._blockers: dict[int, set[int]] = {}
        self._dirty: set[int] = set()
        self._waiting: set[int] = set()  # robots with unplanned legs (kept by _refresh)

    def assign(self, robot: int, now: int, task: int, origin: tuple[int, int],
               destination: tuple[int, int]) -> None:  # fmt: skip
        """Give ``task`` to ``robot`` (free at ``now``), plan it, and retry deferred robots."""
        o, d = (int(c) for c in self.nav._padded_index(np.array([origin, destination])))
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
        return np.stack([flat % self._wp - 1, flat // self._wp - 1], axis=-1).astype(np.int64)

    # ------------------------------------------------------------------ planning
    def _rescue(self, now: int) -> bool:
        """Last resort before reporting a deadlock; True when some robot moved."""
        del now
        return False

    @abstractmethod
    def _plan(
        self, robot: int, now: int, legs: list[Leg], blockers: set[int] | None = None
    ) -> bool:
        """Plan ``robot`` through ``legs`` (and commit) or return False.

        ``blockers`` receives the held cells that made the plan fail, when known.
        """

    def _serve(self, robot: int, now: int) -> bool:
        pending = self._pending(robot)
        tries = [pending] if len(pending) == 1 or not self._partial else [pending, pending[:1]]
        blockers: set[int] = set()
        self._blockers.pop(robot, None)
        self._dirty.discard(robot)
        for attempt in range(2):
            if any(self._plan(robot, now, legs, blockers) for legs in tries):
                self._refresh(robot, now)
                return True
            if attempt == 0 and not self._evacuate_for(robot, now):
                break
        if self._partial:
            self._blockers[robot] = blockers
        self._refresh(robot, now)
        return False

    def _retry(self, now: int, force: bool = False) -> None:
        """Re-plan deferred robots until none makes progress.

        Without ``force``, a SIPP robot is retried only once a cell that blocked its last
        search has been released: nothing else can turn a failed search into a success.
        """
        progress = True
        while progress:
            progress = False
            for robot in self.deferred():
                if not force and robot in self._blockers and robot not in self._dirty:
                    continue
                if self._end(robot) <= now or self._partial:
                    progress |= self._serve(robot, now)

    def _evacuate_for(self, robot: int, now: int) -> bool:
        """Move robots that will not move by themselves off ``robot``'s way.

        First off one shortest route through its pending legs; if nobody on it can be
        moved, off every shortest route (a robot trapped in a pocket on one route may
        leave room on another).
        """
        return any(self._evacuate_from(robot, now, self._route(robot, wide)) for wide in (0, 1))

    def _evacuate_from(self, robot: int, now: int, route: set[int]) -> bool:
        if self._budget <= 0:
            return False
        stuck = [
            k for k in range(self.num_robots)
            if k != robot and self._end(k) <= now and self.timeline[k][-1] in route
            and (self._pending(k) or self.closing)
        ]  # fmt: skip
        moved = False
        for k in stuck:
            taken = self._taken_cells()
            for cell in self._parking_cells(self.timeline[k][-1], route | taken):
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
        """Cells of ``robot``'s single-robot shortest route through its pending legs.

        With ``wide``, the cells of every shortest route: those whose distances from
        and to the ends of a leg add up to its length.
        """
        here = self.timeline[robot][-1]
        cells = {here}
        for leg in self._pending(robot):
            a, b = self._xy(here), self._xy(leg.cell)
            if wide:
                da, db = self.nav.field(*a), self.nav.field(*b)
                on = (da >= 0) & (da + db == da[leg.cell])
                cells.update(np.flatnonzero(on).tolist())
            else:
                cells.update(self.nav._padded_index(self.nav.path(a, b)).tolist())
            here = leg.cell
        return cells

    def _taken_cells(self) -> set[int]:
        taken = {t[-1] for t in self.timeline}
        for legs in self.legs:
            taken.update(leg.cell for leg in legs)
        return taken

    def _parking_cells(self, start: int, avoid: set[int], count: int = 6) -> list[int]:
        """The ``count`` nearest free cells from ``start`` (BFS) not in ``avoid``."""
        seen, queue, found = {start}, deque([start]), []
        while queue and len(found) < count:
            cell = queue.popleft()
            for nxt in (cell + 1, cell - 1, cell + self._wp, cell - self._wp):
                if self._free[nxt] and nxt not in seen:
                    seen.add(nxt)
                    queue.append(nxt)
                    if nxt not in avoid:
                        found.append(nxt)
        return found

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
        goals = [leg.cell for leg in legs]
        fields = [self.nav.field(*self._xy(g)) for g in goals]
        table.release_from(robot, t0)
        try:
            found = sipp_plan(table, self._free, self._wp, start, t0, goals, fields,
                              self._deadline(), blockers)  # fmt: skip
        except PlanningTimeout as exc:
            raise self._timeout(exc, [robot], t0) from None
        if found is None:
            table.reserve(robot, t0, [start])
            return False
        cells, times = found
        table.reserve(robot, t0, cells)
        self._commit(robot, t0, cells, legs, times)
        # The robot's old cell is no longer held forever: wake the robots it blocked.
        self._dirty.update(r for r, held in self._blockers.items() if start in held)
        return True

    def _joint(self, agents: list[int], agent_legs: list[list[Leg]], now: int) -> bool:
        """One CBS call: ``agents`` through their legs from ``now``, the rest standing still."""
        blocked = np.zeros_like(self._grid_free)
        for r in range(self.num_robots):
            if r not in agents:
                x, y = self._xy(self.timeline[r][-1])
                blocked[y, x] = True
        starts = np.array([self._xy(self._at(r, now)) for r in agents], dtype=np.int64)
        goals = [np.array([self._xy(g.cell) for g in gl], dtype=np.int64) for gl in agent_legs]
        try:
            self.cbs_calls += 1
            sol = cbs_solve(self._grid_free, blocked, starts, goals, self._heuristic,
                            self._deadline(), max_nodes=self.max_nodes,
                            max_expansions=EXPANSIONS_PER_NODE * self.max_nodes)  # fmt: skip
        except PlanningTimeout as exc:
            raise self._timeout(exc, agents, now) from None
        if sol is None:
            return False
        for r, gl, path, times in zip(agents, agent_legs, sol.paths, sol.goal_times, strict=True):
            cells = self.nav._padded_index(path).tolist()
            self._commit(r, now, cells, gl, [now + int(t) for t in times])
            self._refresh(r, now)
        return True

    def _heuristic(self, x: int, y: int) -> np.ndarray:
        return self.nav.field(x, y).reshape(self._shape)[1:-1, 1:-1]

    def _at(self, robot: int, t: int) -> int:
        line = self.timeline[robot]
        return line[min(t, len(line) - 1)]

    # ------------------------------------------------------------------ bookkeeping
    _partial = False

    def _pending(self, robot: int) -> list[Leg]:
        return [leg for leg in self.legs[robot] if leg.time is None]

    def _end(self, robot: int) -> int:
        return len(self.timeline[robot]) - 1

    def _xy(self, cell: int) -> tuple[int, int]:
        return cell % self._wp - 1, cell // self._wp - 1

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
        pending = self._pending(robot)
        end = self._end(robot)
        last = next((g for g in reversed(self.legs[robot]) if g.kind != PARK), None)
        if pending:
            self._waiting.add(robot)
        else:
            self._waiting.discard(robot)
        if not pending:
            free = last.time if last is not None and last.time is not None else end
            self.free_at[robot] = self.estimated_free_at[robot] = max(free, 0)
            return
        self.free_at[robot] = np.inf
        here, total = self._xy(self.timeline[robot][-1]), 0.0
        for leg in pending:
            there = self._xy(leg.cell)
            total += float(self.nav.distance(np.array([here]), np.array([there]))[0])
            here = there
        self.estimated_free_at[robot] = max(now, end) + total

    def _blocked_message(self, now: int) -> str:
        parts = []
        for r in self.deferred()[:5]:
            leg = self._pending(r)[0]
            x, y = self._xy(leg.cell)
            at = self._xy(self.timeline[r][-1])
            parts.append(
                f"robot {r} at (x={at[0]}, y={at[1]}) cannot reach the {_KINDS[leg.kind]} "
                f"cell (x={x}, y={y}) of task {leg.task}"
            )
        return (
            f"navigator {self.name}: the robots are deadlocked at t={now}: "
            + "; ".join(parts)
            + " (robots hold their cells and none of those in the way could be moved aside)"
        )


class SIPPFleet(Fleet):
    """Prioritized planning with SIPP over a reservation table of all trajectories."""

    name = "sipp"
    _partial = True

    def reset(self, starts: np.ndarray, free_at: np.ndarray, num_tasks: int) -> None:
        super().reset(starts, free_at, num_tasks)
        self.table = ReservationTable(self.num_robots)
        for robot, line in enumerate(self.timeline):
            self.table.reserve(robot, 0, line)

    def _plan(
        self, robot: int, now: int, legs: list[Leg], blockers: set[int] | None = None
    ) -> bool:
        return self._plan_around(self.table, robot, max(now, self._end(robot)), legs, blockers)

    def _rescue(self, now: int) -> bool:
        """Prioritized planning is stuck: plan the deferred robots jointly (one CBS call),
        with the robots that stand in their way going to parking cells."""
        deferred = [r for r in self.deferred() if self._end(r) <= now]
        if not deferred:
            return False
        route = set().union(*(self._route(r, wide=True) for r in deferred))
        taken = self._taken_cells()
        agents, agent_legs = list(deferred), [self._pending(r) for r in deferred]
        for k in range(self.num_robots):
            here = self.timeline[k][-1]
            idle = self.closing and not self._pending(k) and self._end(k) <= now
            if k in deferred or here not in route or not idle:
                continue
            # Off every route if possible; otherwise CBS orders who passes first.
            parking = self._parking_cells(here, taken | route, 1) or self._parking_cells(
                here, taken, 1
            )
            if not parking:
                return False
            taken.add(parking[0])
            agents.append(k)
            agent_legs.append([Leg(parking[0], -1, PARK)])
        for r in agents:
            self.table.release_from(r, now)
        if not self._joint(agents, agent_legs, now):
            for r in agents:
                self.table.reserve(r, now, [self.timeline[r][-1]])
            return False
        for r, gl in zip(agents, agent_legs, strict=True):
            if gl[0].kind == PARK:
                self.legs[r] += gl
                self.evacuations += 1
            self.table.reserve(r, now, self.timeline[r][now:])
            self._refresh(r, now)
        return True


class CBSFleet(Fleet):
    """Conflict-Based Search, re-planned jointly over all moving robots at each assignment."""

    name = "cbs"

    def __init__(
        self, navigator: AStarNavigator, num_robots: int, time_limit: float, max_nodes: int
    ) -> None:
        super().__init__(navigator, num_robots, time_limit)
        self.max_nodes = max_nodes

    def _plan(
        self, robot: int, now: int, legs: list[Leg], blockers: set[int] | None = None
    ) -> bool:
        del blockers  # CBS re-plans others too: any commit may unblock a robot
        moving = [r for r in range(self.num_robots) if r != robot and self._end(r) > now]
        waiting = [r for r in self.deferred() if r != robot and r not in moving]
        # Deferred robots join the search when they can: CBS may find room for all.
        if waiting and self._solve(robot, now, legs, moving + waiting):
            return True
        if self._solve(robot, now, legs, moving):
            return True
        # No joint plan within the node budget (or none exists with everyone holding
        # their goals): plan this robot alone around the others' current paths.
        table = ReservationTable(self.num_robots)
        for r in range(self.num_robots):
            if r != robot:
                line = self.timeline[r]
                table.reserve(r, now, line[min(now, len(line) - 1) :])
        if self._plan_around(table, robot, now, legs):
            self.fallbacks += 1
            return True
        return False

    def _solve(self, robot: int, now: int, legs: list[Leg], others: list[int]) -> bool:
        agent_legs = [legs] + [
            [g for g in self.legs[r] if g.time is None or g.time > now] for r in others
        ]
        return self._joint([robot, *others], agent_legs, now)
