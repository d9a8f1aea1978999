"""Conflict-Based Search's constraints and low level: space-time A* for one agent.

A conflict splits into one new constraint per agent (:func:`split_conflict`; the rules
are in :mod:`rtaw_marl.sim.mapf.cbs`). The low level plans one agent under its
constraints.

A state is ``(cell, t, goal index)``. The heuristic is the distance to the next goal
plus the distances between the remaining goals (exact BFS fields). Ties are broken by
fewer conflicts with the other agents' paths (a conflict avoidance table), then by
larger ``g``. Past the agent's latest constraint time the problem is static, so states
from then on are keyed without time (only the earliest arrival matters): the state
space is finite and the search ends, returning ``None``, when no path exists.

An agent's final goal counts only once it may stay there for good: after every vertex
constraint on that cell and after its ``finish_after`` time.
"""

from __future__ import annotations

import heapq
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace

from rtaw_marl.errors import PlanningTimeout

__all__ = ["Agent", "Conflict", "Constraints", "OutOfBudget", "low_level", "split_conflict"]

#: Low-level expansions between two deadline checks.
CHECK_EVERY = 256
#: Multiplier packing (time, conflicts) into one int; conflicts never reach it.
_CONF_SPAN = 1 << 32


@dataclass
class Agent:
    """Static data of one agent: start cell, goal cells and heuristic rows."""

    start: int
    goals: list[int]
    h: list[list[int]]  # h[k][c]: distance to goal k plus the remaining goal chain


@dataclass
class Constraints:
    """One agent's constraints, flat-encoded (``n`` = number of grid cells).

    ``vertex`` holds ``t * n + cell``; ``edge`` holds ``(t * n + a) * n + b``;
    ``after`` maps a cell to the time from which the agent may never be on it again.
    """

    vertex: frozenset[int] = frozenset()
    edge: frozenset[int] = frozenset()
    after: dict[int, int] = field(default_factory=dict)
    finish_after: int = -1  # the path must end (at the last goal) after this time
    latest: int = -1  # largest constraint time


#: ``(kind, i, j, a, b, t)``: kind ``"v"`` (``a == b``) or ``"e"`` (``i`` moves ``a -> b``).
Conflict = tuple[str, int, int, int, int, int]


def split_conflict(
    conflict: Conflict, paths: list[list[int]], cons: list[Constraints], n: int
) -> list[tuple[int, Constraints]]:
    """The two ``(agent, new constraints)`` children of a conflict (rules: :mod:`.cbs`).

    A target conflict's second child is sound because an agent that finishes on the
    cell by ``t`` occupies it at every time from ``t`` on.
    """
    kind, i, j, a, b, t = conflict
    out = []
    if kind == "e":
        for agent, src, dst in ((i, a, b), (j, b, a)):
            old = cons[agent]
            edge = old.edge | {(t * n + src) * n + dst}
            out.append((agent, replace(old, edge=edge, latest=max(old.latest, t))))
        return out
    parked = j if len(paths[j]) <= t + 1 else i if len(paths[i]) <= t + 1 else -1
    for agent in (i, j):
        old = cons[agent]
        if agent == parked:
            finish = max(old.finish_after, t)
            out.append((agent, replace(old, finish_after=finish, latest=max(old.latest, t))))
        elif parked >= 0:
            after = dict(old.after)
            after[a] = min(after.get(a, t), t)
            out.append((agent, replace(old, after=after, latest=max(old.latest, t))))
        else:
            vertex = old.vertex | {t * n + a}
            out.append((agent, replace(old, vertex=vertex, latest=max(old.latest, t))))
    return out


class OutOfBudget(Exception):
    """The low-level expansion budget of one CBS call is spent."""


def low_level(
    agent: Agent,
    cons: Constraints,
    others: Sequence[list[int]],
    neighbours: Callable[[int], list[int]],
    n: int,
    deadline: float,
    budget: list[int],
) -> tuple[list[int], list[int]] | None:
    """Space-time A* for one agent under its constraints.

    Args:
        agent: The agent's start, goals and heuristic rows.
        cons: Its constraints.
        others: The other agents' current paths (cells), for conflict avoidance.
        neighbours: Cell -> traversable cells reachable in one step, itself included.
        n: Number of grid cells.
        deadline: ``time.perf_counter()`` value past which to give up.
        budget: ``[expansions left]`` for the whole CBS call, decremented here by the
            exact number of expansions.

    Returns:
        ``(path, goal_times)`` in cells, or ``None`` when no path exists.

    Raises:
        PlanningTimeout: The deadline passed (re-raised by the caller with context).
        OutOfBudget: The call's expansion budget is spent.
    """
    search = _SpaceTimeSearch(agent, cons, others, n)
    if budget[0] < 0:
        raise OutOfBudget
    return search.run(neighbours, deadline, budget)


def _avoidance_table(
    others: Sequence[list[int]], n: int
) -> tuple[dict[int, int], set[int], dict[int, int]]:
    """Conflict avoidance table of the other agents' paths.

    Returns:
        ``(vertex, edge, parked)``: agents per ``t * n + cell``; reversed moves
        ``(t * n + b) * n + a`` of agents moving ``a -> b`` at ``t``; and per final
        cell the earliest time an agent parks there for good.
    """
    cat_v: dict[int, int] = {}
    cat_e: set[int] = set()
    parked: dict[int, int] = {}
    for p in others:
        for t, c in enumerate(p[:-1]):
            key = t * n + c
            cat_v[key] = cat_v.get(key, 0) + 1
            nxt = p[t + 1]
            if nxt != c:
                cat_e.add((t * n + nxt) * n + c)
        end = len(p) - 1
        if parked.get(p[-1], end + 1) > end:
            parked[p[-1]] = end
    return cat_v, cat_e, parked


class _SpaceTimeSearch:
    """One low-level search: the constants of the agent and its constraints."""

    def __init__(
        self, agent: Agent, cons: Constraints, others: Sequence[list[int]], n: int
    ) -> None:
        self.agent = agent
        self.cons = cons
        self.n = n
        self.num_goals = len(agent.goals)
        self.last = self.num_goals - 1
        self.final = agent.goals[self.last]
        # The final goal counts only once the agent may stay on it for good.
        self.last_final = max(
            [cons.finish_after, *(v // n for v in cons.vertex if v % n == self.final)]
        )
        self.tcap = cons.latest + 1  # from here on nothing depends on time
        self.fmin = self.last_final + 1
        self.cat_v, self.cat_e, self.parked = _avoidance_table(others, n)

    def advance(self, c: int, t: int, k: int) -> int:
        """Goal index after standing on ``c`` at ``t`` with ``k`` goals visited."""
        goals, last = self.agent.goals, self.last
        while k < last and c == goals[k]:
            k += 1
        if k == last and c == self.final and t > self.last_final:
            k = self.num_goals
        return k

    def run(
        self, neighbours: Callable[[int], list[int]], deadline: float, budget: list[int]
    ) -> tuple[list[int], list[int]] | None:
        """The A* loop; states are keyed ``((min(t, tcap) * span + k) * n + c)``."""
        cons, n, goals, hrows = self.cons, self.n, self.agent.goals, self.agent.h
        vcons, econs, after = cons.vertex, cons.edge, cons.after
        cat_v, cat_e, parked = self.cat_v, self.cat_e, self.parked
        num_goals, final, tcap, fmin = self.num_goals, self.final, self.tcap, self.fmin
        advance, span, start = self.advance, num_goals + 1, self.agent.start
        k0 = advance(start, 0, 0)
        h0 = 0 if k0 == num_goals else hrows[k0][start]
        best: dict[int, int] = {k0 * n + start: 0}  # time 0, no conflicts
        heap: list[tuple[int, int, int, int, int, int]] = [(max(h0, fmin), 0, 0, start, k0, -1)]
        nodes: list[tuple[int, int, int]] = []  # expanded (cell, goal index, parent)
        expansions = 0
        while heap:
            _, conf, neg_t, c, k, parent = heapq.heappop(heap)
            t = -neg_t
            key = ((t if t < tcap else tcap) * span + k) * n + c
            if best.get(key) != t * _CONF_SPAN + conf:
                continue  # stale or already expanded
            best[key] = -1
            nodes.append((c, k, parent))
            if k == num_goals:
                budget[0] -= expansions % CHECK_EVERY
                return _reconstruct(nodes, num_goals)
            expansions += 1
            if expansions % CHECK_EVERY == 0:
                _charge(deadline, budget)
            me, t1 = len(nodes) - 1, t + 1
            base_v, base_e = t1 * n, (t * n + c) * n
            for c2 in neighbours(c):
                if base_v + c2 in vcons or base_e + c2 in econs:
                    continue
                if after and t1 >= after.get(c2, t1 + 1):
                    continue
                k2 = advance(c2, t1, k) if (c2 == goals[k] or c2 == final) else k
                conf2 = conf + cat_v.get(base_v + c2, 0)
                if base_e + c2 in cat_e:
                    conf2 += 1
                pt = parked.get(c2)
                if pt is not None and t1 >= pt:
                    conf2 += 1
                key2 = ((t1 if t1 < tcap else tcap) * span + k2) * n + c2
                val = t1 * _CONF_SPAN + conf2
                old = best.get(key2)
                if old is not None and val >= old:  # -1 marks expanded states
                    continue
                best[key2] = val
                f2 = t1 if k2 == num_goals else t1 + hrows[k2][c2]
                heapq.heappush(heap, (f2 if f2 > fmin else fmin, conf2, -t1, c2, k2, me))
        budget[0] -= expansions % CHECK_EVERY
        return None


def _charge(deadline: float, budget: list[int]) -> None:
    """Every :data:`CHECK_EVERY` expansions: check the deadline and charge the budget."""
    if time.perf_counter() > deadline:
        raise PlanningTimeout("low-level search ran past its time limit")
    budget[0] -= CHECK_EVERY
    if budget[0] < 0:
        raise OutOfBudget


def _reconstruct(nodes: list[tuple[int, int, int]], num_goals: int) -> tuple[list[int], list[int]]:
    """Walk parent links back from the last node; goal ``g`` is met where ``k`` passes it."""
    cells: list[int] = []
    ks: list[int] = []
    i = len(nodes) - 1
    while i >= 0:
        c, k, i = nodes[i]
        cells.append(c)
        ks.append(k)
    cells.reverse()
    ks.reverse()
    goal_times = [0] * num_goals
    g = 0
    for t, k in enumerate(ks):
        while g < k:
            goal_times[g] = t
            g += 1
    return cells, goal_times
