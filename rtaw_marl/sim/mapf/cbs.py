"""Conflict-Based Search (Sharon et al. 2015) for agents with ordered goal sequences.

Model: discrete time, one step per second; at each step an agent moves to a
4-connected neighbour or waits. A cell is traversable when it is free on the
:class:`~rtaw_marl.sim.mapf.grid.Grid` and not ``blocked``. Each agent visits its goals
in order (goal ``k`` counts once the agent stands on it after goals ``0 .. k-1``; a
goal equal to the current cell at time 0 is visited at time 0) and, once at its last
goal, stays there forever.

Conflict rules, with ``pos_i(t)`` the cell of agent ``i`` at time ``t`` (its last cell
for every ``t`` past the end of its path):

* vertex conflict: ``pos_i(t) == pos_j(t)``; this includes an agent passing through
  the final goal of an agent already parked there;
* edge conflict: ``pos_i(t) == pos_j(t + 1)`` and ``pos_i(t + 1) == pos_j(t)`` with a
  real move (agents swapping cells). Following into a just-vacated cell is allowed.

High level: best-first search on the sum of costs (arrival times at the last goals),
ties broken by fewer conflicts. Each node keeps, per conflicting pair of agents, its
earliest conflict. Among the earliest few, the first cardinal one (both children cost
more, found by planning them) is split, else the first semi-cardinal one, else the
earliest. A split adds one constraint to each of the two agents, one per child:

* vertex conflict at ``(cell, t)``: the agent may not be on ``cell`` at ``t``. On an
  agent's final cell this also means it may finish there only after ``t``;
* edge conflict: the agent may not move ``a -> b`` between ``t`` and ``t + 1``;
* target conflict (a vertex conflict with an agent already parked on its final
  cell): either the parked agent finishes after ``t`` (a length constraint; it may
  still pass the cell at ``t``) or the other agent may never be on the cell from
  ``t`` on. Every solution satisfies one of the two (a plain vertex split would only
  push the parked agent's arrival one step per tree level).

A child with the parent's cost and fewer conflicts replaces the parent's path instead
of branching (bypass). Children whose agent has no path, or whose constraint set is
already in the tree, are dropped. All of this keeps the search optimal. The constraints,
the split and the low level are in :mod:`rtaw_marl.sim.mapf.cbs_low`.

Two deterministic budgets bound a call (``max_nodes`` high-level nodes and
``max_expansions`` low-level expansions), besides the wall-clock deadline; a
:class:`CBSStats` reports what a call spent.
"""

from __future__ import annotations

import heapq
import time
from collections.abc import Collection, Sequence
from dataclasses import dataclass

import numpy as np

from rtaw_marl.errors import PlanningTimeout
from rtaw_marl.sim.mapf.cbs_low import (
    Agent,
    Conflict,
    Constraints,
    OutOfBudget,
    low_level,
    split_conflict,
)
from rtaw_marl.sim.mapf.grid import Grid

__all__ = ["CBSSolution", "CBSStats", "cbs_solve"]

#: Conflicts of a high-level node examined when looking for a cardinal one.
_CANDIDATES = 4


@dataclass(frozen=True)
class CBSSolution:
    """A conflict-free joint plan.

    Attributes:
        paths: Per agent ``int64 [L_i + 1]`` cells at relative times ``0 .. L_i``;
            ``L_i`` is the arrival time at its last goal.
        goal_times: Per agent ``int64 [G_i]`` arrival time of each goal, in order.
        expanded: High-level nodes taken from the open list (1 when the first plan
            has no conflict).
    """

    paths: list[np.ndarray]
    goal_times: list[np.ndarray]
    expanded: int


@dataclass
class CBSStats:
    """What one :func:`cbs_solve` call spent (filled in by the call).

    Attributes:
        nodes: High-level nodes expanded.
        expansions: Low-level A* expansions, over all agents and nodes.
        exhausted: ``"max_nodes"`` or ``"max_expansions"`` when that budget stopped the
            search, else ``None``.
    """

    nodes: int = 0
    expansions: int = 0
    exhausted: str | None = None


@dataclass
class _Node:
    cost: int
    paths: list[list[int]]
    goal_times: list[list[int]]
    cons: list[Constraints]


#: An open-list entry: ``(cost, conflict count, tie, node, its earliest conflicts)``.
_Entry = tuple[int, int, int, _Node, list[Conflict]]


def cbs_solve(
    grid: Grid,
    starts: Sequence[int],
    goals: Sequence[Sequence[int]],
    deadline: float,
    *,
    blocked: Collection[int] = (),
    max_nodes: int | None = None,
    max_expansions: int | None = None,
    stats: CBSStats | None = None,
) -> CBSSolution | None:
    """Plan conflict-free paths minimising the sum of arrival times at the last goals.

    Args:
        grid: The grid; its distance fields (ignoring ``blocked``) are the heuristic.
        starts: ``A`` start cells at relative time 0.
        goals: Per agent its goal cells (at least one), visited in order.
        deadline: ``time.perf_counter()`` value past which to give up.
        blocked: Cells occupied forever (parked robots): extra obstacles.
        max_nodes: High-level nodes to expand at most; past it the search gives up and
            returns ``None`` (a deterministic budget, unlike the deadline).
        max_expansions: Low-level A* expansions over the whole call at most (charged in
            steps of a few hundred); past it the search gives up and returns ``None``.
        stats: When given, receives the nodes and expansions spent.

    Returns:
        An optimal :class:`CBSSolution`, or ``None`` when the instance is infeasible
        (a start or goal not traversable, a goal unreachable, two agents sharing a
        start or a final goal, or no plan found once the constraint tree is exhausted)
        or a budget (``max_nodes``, ``max_expansions``) was spent without a solution.

    Raises:
        PlanningTimeout: The search ran past ``deadline``.
    """
    stats = CBSStats() if stats is None else stats
    stats.nodes, stats.expansions, stats.exhausted = 0, 0, None
    ok = grid.free.ravel().copy()
    ok[list(blocked)] = False
    agents = _agents(grid, ok.tolist(), starts, goals)
    if agents is None:
        return None
    search = _HighLevel(grid, ok.tolist(), agents, deadline, max_nodes, max_expansions)
    try:
        return search.run()
    except OutOfBudget:
        search.exhausted = "max_expansions"
        return None
    finally:
        stats.nodes, stats.exhausted = search.expanded, search.exhausted
        stats.expansions = search.initial_budget - search.budget[0]


def _agents(
    grid: Grid, ok: list[bool], starts: Sequence[int], goals: Sequence[Sequence[int]]
) -> list[Agent] | None:
    """Agents with their heuristic rows, or ``None`` when the instance is plainly infeasible."""
    flat_starts = [int(s) for s in starts]
    if len(set(flat_starts)) < len(flat_starts) or not all(ok[s] for s in flat_starts):
        return None
    agents: list[Agent] = []
    finals: set[int] = set()
    for s, agent_goals in zip(flat_starts, goals, strict=True):
        cells = [int(c) for c in agent_goals]
        if not cells or not all(ok[c] for c in cells) or cells[-1] in finals:
            return None
        finals.add(cells[-1])
        fields = [grid.field(c) for c in cells]
        legs = [int(fields[0][s])] + [int(fields[k + 1][cells[k]]) for k in range(len(cells) - 1)]
        if min(legs) < 0:
            return None
        suffix = [sum(legs[k + 1 :]) for k in range(len(cells))]  # chain after goal k
        hrows = [(f.astype(np.int64) + sk).tolist() for f, sk in zip(fields, suffix, strict=True)]
        agents.append(Agent(s, cells, hrows))
    return agents


class _HighLevel:
    """The constraint-tree search of one :func:`cbs_solve` call."""

    def __init__(
        self,
        grid: Grid,
        ok: list[bool],
        agents: list[Agent],
        deadline: float,
        max_nodes: int | None,
        max_expansions: int | None,
    ) -> None:
        self.grid = grid
        self.ok = ok
        self.n = grid.size
        self.agents = agents
        self.deadline = deadline
        self.max_nodes = max_nodes
        self.initial_budget = max_expansions if max_expansions is not None else 1 << 62
        self.budget = [self.initial_budget]
        self.expanded = 0
        self.exhausted: str | None = None
        self.tie = 0
        self.seen: set[tuple] = set()
        self._neighbours: dict[int, list[int]] = {}

    def run(self) -> CBSSolution | None:
        """Best-first search over constraint-tree nodes."""
        self._check_deadline()
        root = self._root()
        if root is None:
            return None
        open_list: list[_Entry] = [root]
        while open_list:
            self._check_deadline()
            if self.max_nodes is not None and self.expanded >= self.max_nodes:
                self.exhausted = "max_nodes"
                return None
            _, count, _, node, conflicts = heapq.heappop(open_list)
            self.expanded += 1
            children = self._resolve(node, count, conflicts)
            if children is None:
                return _solution(node, self.expanded)
            for entry in children:
                # Skip a child whose constraint set is already in the tree (reached in
                # another order): the first copy covers the same solutions.
                signature = tuple(
                    (c.vertex, c.edge, frozenset(c.after.items()), c.finish_after)
                    for c in entry[3].cons
                )
                if signature not in self.seen:
                    self.seen.add(signature)
                    heapq.heappush(open_list, entry)
        return None

    def _root(self) -> _Entry | None:
        """Each agent planned in turn, avoiding (softly) the agents planned before it."""
        cons = [Constraints() for _ in self.agents]
        paths: list[list[int]] = []
        goal_times: list[list[int]] = []
        for i in range(len(self.agents)):
            res = self._plan(i, cons[i], paths)
            if res is None:
                return None
            paths.append(res[0])
            goal_times.append(res[1])
        count, conflicts = _conflicts(paths)
        cost = sum(len(p) - 1 for p in paths)
        return cost, count, 0, _Node(cost, paths, goal_times, cons), conflicts

    def _resolve(self, node: _Node, count: int, conflicts: list[Conflict]) -> list[_Entry] | None:
        """The children to push for ``node``, or ``None`` once ``node`` is conflict-free.

        Bypasses replace ``node``'s paths in place (fewer conflicts, same cost), so a node
        may become a solution without branching.
        """
        while conflicts:
            children, bypass = self._choose(node, count, conflicts)
            if bypass is None:
                return children
            count, conflicts = bypass
        return None

    def _choose(
        self, node: _Node, count: int, conflicts: list[Conflict]
    ) -> tuple[list[_Entry], tuple[int, list[Conflict]] | None]:
        """Split a cardinal conflict if one of the earliest few is, else semi-cardinal,
        else the earliest; or adopt a bypass (then returns its ``(count, conflicts)``)."""
        best: tuple[int, list[_Entry]] | None = None
        for conflict in conflicts[:_CANDIDATES]:
            children, bypass = self._children(node, count, conflict)
            if bypass is not None:
                return [], bypass
            # Children that do not cost more than the node: 0 for a cardinal conflict.
            rank = len(children) - sum(entry[0] > node.cost for entry in children)
            if best is None or rank < best[0]:
                best = (rank, children)
            if rank == 0:
                break
        assert best is not None
        return best[1], None

    def _children(
        self, node: _Node, count: int, conflict: Conflict
    ) -> tuple[list[_Entry], tuple[int, list[Conflict]] | None]:
        """The children of splitting ``conflict``, or a bypass adopted into ``node``."""
        children: list[_Entry] = []
        for agent, cons in split_conflict(conflict, node.paths, node.cons, self.n):
            res = self._plan(agent, cons, node.paths)
            if res is None:
                continue
            paths = list(node.paths)
            goal_times = list(node.goal_times)
            paths[agent], goal_times[agent] = res
            cost = node.cost - len(node.paths[agent]) + len(res[0])
            child_count, child_conflicts = _conflicts(paths)
            if cost == node.cost and child_count < count:
                # Bypass: the new path also meets the node's constraints; adopt it.
                node.paths, node.goal_times = paths, goal_times
                return [], (child_count, child_conflicts)
            all_cons = list(node.cons)
            all_cons[agent] = cons
            self.tie += 1
            child = _Node(cost, paths, goal_times, all_cons)
            children.append((cost, child_count, self.tie, child, child_conflicts))
        return children, None

    def _plan(
        self, i: int, cons: Constraints, paths: list[list[int]]
    ) -> tuple[list[int], list[int]] | None:
        """Low-level path of agent ``i`` under ``cons``, avoiding the others' ``paths``."""
        others = paths[:i] + paths[i + 1 :]
        try:
            return low_level(
                self.agents[i], cons, others, self._neighbours_of, self.n, self.deadline,
                self.budget,
            )  # fmt: skip
        except PlanningTimeout:
            raise self._timeout() from None

    def _neighbours_of(self, c: int) -> list[int]:
        """``c`` itself (a wait) and its traversable 4-neighbours."""
        out = self._neighbours.get(c)
        if out is None:
            ok = self.ok
            out = [c, *(d for d in self.grid.neighbours(c) if ok[d])]
            self._neighbours[c] = out
        return out

    def _check_deadline(self) -> None:
        if time.perf_counter() > self.deadline:
            raise self._timeout()

    def _timeout(self) -> PlanningTimeout:
        return PlanningTimeout(
            f"CBS ran past its time limit after {self.expanded} high-level nodes"
        )


def _conflicts(paths: list[list[int]]) -> tuple[int, list[Conflict]]:
    """Count all pairwise conflicts and list each conflicting pair's earliest one.

    Returns:
        ``(count, conflicts)``: ``conflicts`` holds, per conflicting pair of agents, its
        earliest conflict ``("v", i, j, cell, cell, t)`` or ``("e", i, j, a, b, t)``
        (``i`` moves ``a -> b`` and ``j`` ``b -> a`` at ``t``), sorted by time; empty
        when the paths are conflict-free.
    """
    num = len(paths)
    if num < 2:
        return 0, []
    horizon = max(len(p) for p in paths)
    pos = np.empty((num, horizon), dtype=np.int64)
    for i, p in enumerate(paths):
        pos[i, : len(p)] = p
        pos[i, len(p) :] = p[-1]
    iu, ju = np.triu_indices(num, 1)
    pi, pj = pos[iu], pos[ju]
    vert = pi == pj
    edge = (pi[:, :-1] == pj[:, 1:]) & (pi[:, 1:] == pj[:, :-1]) & (pi[:, :-1] != pi[:, 1:])
    count = int(vert.sum()) + int(edge.sum())
    if count == 0:
        return 0, []
    v_any, e_any = vert.any(axis=1), edge.any(axis=1)
    tv = np.where(v_any, vert.argmax(axis=1), horizon)
    te = np.where(e_any, edge.argmax(axis=1), horizon)
    out = []
    # An edge conflict at te spans te -> te + 1, so it comes after a vertex one at te.
    for k in np.flatnonzero(v_any | e_any).tolist():
        i, j, t_v, t_e = int(iu[k]), int(ju[k]), int(tv[k]), int(te[k])
        if t_v <= t_e:
            c = int(pi[k, t_v])
            out.append((2 * t_v, ("v", i, j, c, c, t_v)))
        else:
            out.append((2 * t_e + 1, ("e", i, j, int(pi[k, t_e]), int(pi[k, t_e + 1]), t_e)))
    out.sort()
    return count, [c for _, c in out]


def _solution(node: _Node, expanded: int) -> CBSSolution:
    """A conflict-free node's paths and goal times as arrays."""
    paths = [np.asarray(p, dtype=np.int64) for p in node.paths]
    goal_times = [np.asarray(g, dtype=np.int64) for g in node.goal_times]
    return CBSSolution(paths=paths, goal_times=goal_times, expanded=expanded)
