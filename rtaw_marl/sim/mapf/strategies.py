"""The two planning strategies of a :class:`~rtaw_marl.sim.mapf.fleet.Fleet`.

:class:`SIPPFleet`
    Prioritized planning: each newly assigned robot runs SIPP around all earlier
    trajectories (kept in a reservation table), which never change. A robot that can
    reach its origin but not its destination goes to the origin and is deferred there.
    A deferred robot is retried only once a cell that blocked its last search has been
    released: nothing else can turn a failed search into a success. When every robot
    waits and no single move helps, one joint CBS call plans the waiting robots and
    those in their way (:meth:`SIPPFleet._rescue`).
:class:`CBSFleet`
    Conflict-Based Search over every moving robot at each assignment: trajectories are
    re-planned jointly from the current time, the past never changes. CBS is
    exponential in the number of conflicts and narrow aisles make some joint problems
    very hard, so a call has a budget of high-level nodes (and of low-level expansions,
    :data:`~rtaw_marl.sim.mapf.fleet.EXPANSIONS_PER_NODE` per node); past it (or when
    no joint plan exists) the new robot plans alone around the others' current paths,
    as SIPP would, and :attr:`Fleet.fallbacks` counts how often.
"""

from __future__ import annotations

import numpy as np

from rtaw_marl.sim.mapf.evacuation import parking_cells
from rtaw_marl.sim.mapf.fleet import PARK, Fleet, Leg
from rtaw_marl.sim.mapf.grid import Grid
from rtaw_marl.sim.mapf.reservations import ReservationTable

__all__ = ["RESCUE_MAX_NODES", "CBSFleet", "SIPPFleet"]

#: High-level node budget of SIPP's joint CBS rescue call.
RESCUE_MAX_NODES = 200


class SIPPFleet(Fleet):
    """Prioritized planning with SIPP over a reservation table of all trajectories.

    Args:
        grid: The grid the robots move on.
        num_robots: ``M``.
        time_limit: Seconds one planning call may take.
    """

    name = "sipp"

    def __init__(self, grid: Grid, num_robots: int, time_limit: float) -> None:
        super().__init__(grid, num_robots, time_limit, max_nodes=RESCUE_MAX_NODES)

    def reset(self, starts: np.ndarray, free_at: np.ndarray, num_tasks: int) -> None:
        super().reset(starts, free_at, num_tasks)
        self.table = ReservationTable(self.num_robots)
        for robot, line in enumerate(self.timeline):
            self.table.reserve(robot, 0, line)
        # Deferred robot -> held cells that blocked its last search, and the deferred
        # robots to retry because one of those cells was released since.
        self._blockers: dict[int, set[int]] = {}
        self._dirty: set[int] = set()

    def _plan(
        self, robot: int, now: int, legs: list[Leg], blockers: set[int] | None = None
    ) -> bool:
        # A robot still moving plans from the end of its committed trajectory.
        return self._plan_around(self.table, robot, max(now, self._end(robot)), legs, blockers)

    def _attempts(self, pending: list[Leg]) -> list[list[Leg]]:
        # Reaching the origin alone is progress when only the destination is blocked.
        return [pending] if len(pending) == 1 else [pending, pending[:1]]

    def _may_retry(self, robot: int, now: int, force: bool) -> bool:
        del now  # SIPP plans from the end of a moving robot's trajectory
        return force or robot not in self._blockers or robot in self._dirty

    def _on_serve(self, robot: int) -> None:
        self._blockers.pop(robot, None)
        self._dirty.discard(robot)

    def _on_blocked(self, robot: int, blockers: set[int]) -> None:
        self._blockers[robot] = blockers

    def _on_released(self, cell: int) -> None:
        # Wake the robots whose last search that cell blocked.
        self._dirty.update(r for r, held in self._blockers.items() if cell in held)

    def _rescue(self, now: int) -> bool:
        """Prioritized planning is stuck: plan the deferred robots jointly (one CBS call),
        with the robots that stand in their way going to parking cells."""
        deferred = [r for r in self.deferred() if self._end(r) <= now]
        if not deferred:
            return False
        party = self._rescue_party(deferred, now)
        if party is None:
            return False
        agents, agent_legs = party
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

    def _rescue_party(
        self, deferred: list[int], now: int
    ) -> tuple[list[int], list[list[Leg]]] | None:
        """The agents of a rescue call and their legs: the deferred robots, plus each
        idle robot on their routes with a parking cell; ``None`` if one has nowhere to go."""
        route = set().union(*(self._route(r, wide=True) for r in deferred))
        taken = self._taken()
        agents, agent_legs = list(deferred), [self._pending(r) for r in deferred]
        for k in range(self.num_robots):
            here = self.timeline[k][-1]
            idle = self.closing and not self._pending(k) and self._end(k) <= now
            if k in deferred or here not in route or not idle:
                continue
            # Off every route if possible; otherwise CBS orders who passes first.
            parking = parking_cells(self.grid, here, taken | route, 1) or parking_cells(
                self.grid, here, taken, 1
            )
            if not parking:
                return None
            taken.add(parking[0])
            agents.append(k)
            agent_legs.append([Leg(parking[0], -1, PARK)])
        return agents, agent_legs


class CBSFleet(Fleet):
    """Conflict-Based Search, re-planned jointly over all moving robots at each assignment.

    Args:
        grid: The grid the robots move on.
        num_robots: ``M``.
        time_limit: Seconds one planning call may take.
        max_nodes: High-level CBS nodes per call; past it the robot plans alone.
    """

    name = "cbs"

    def __init__(self, grid: Grid, num_robots: int, time_limit: float, max_nodes: int) -> None:
        super().__init__(grid, num_robots, time_limit, max_nodes=max_nodes)

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
        """One joint call: ``robot`` through ``legs`` with ``others`` through theirs."""
        agent_legs = [legs] + [
            [g for g in self.legs[r] if g.time is None or g.time > now] for r in others
        ]
        return self._joint([robot, *others], agent_legs, now)
