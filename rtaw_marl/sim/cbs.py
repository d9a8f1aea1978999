"""Conflict-Based Search (Sharon et al. 2015) for agents with ordered goal sequences.

Model: discrete time, one step per second; at each step an agent moves to a
4-connected neighbour or waits. A cell ``(x, y)`` is traversable when ``free[y, x]``
and not ``blocked[y, x]``. Each agent visits its goals in order (goal ``k`` counts once
the agent stands on it after goals ``0 .. k-1``; a goal equal to the current cell at
time 0 is visited at time 0) and, once at its last goal, stays there forever.

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
  agent's final cell this also means it may finish there only after ``t``: the low
  level reaches the final goal only at a time after which it has no vertex
  constraint on that cell;
* edge conflict: the agent may not move ``a -> b`` between ``t`` and ``t + 1``;
* target conflict (a vertex conflict with an agent already parked on its final
  cell): either the parked agent finishes after ``t`` (a length constraint; it may
  still pass the cell at ``t``) or the other agent may never be on the cell from
  ``t`` on. Every solution satisfies one of the two (a plain vertex split would only
  push the parked agent's arrival one step per tree level).

A child with the parent's cost and fewer conflicts replaces the parent's path instead
of branching (bypass). Children whose agent has no path, or whose constraint set is
already in the tree, are dropped. All of this keeps the search optimal.

Low level: space-time A* on ``(cell, t, goal index)`` with heuristic = distance to the
next goal + distances between the remaining goals (exact BFS fields on ``free``),
ties broken by fewer conflicts with the other agents' paths (a conflict avoidance
table), then by larger ``g``. Past the agent's latest constraint time the problem is
static, so states from then on are keyed without time (only the earliest arrival
matters): the state space is finite and the search ends, returning ``None``, when no
path exists.
"""

from __future__ import annotations

import heapq
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from rtaw_marl.errors import PlanningTimeout

__all__ = ["CBSSolution", "cbs_solve"]

#: Low-level expansions between two deadline checks.
_CHECK_EVERY = 256
#: Conflicts of a high-level node examined when looking for a cardinal one.
_CANDIDATES = 4
#: Multiplier packing (time, conflicts) into one int; conflicts never reach it.
_CONF_SPAN = 1 << 32


@dataclass(frozen=True)
class CBSSolution:
    """A conflict-free joint plan.

    Attributes:
        paths: Per agent ``int64 [L_i + 1, 2]`` cells ``(x, y)`` at relative times
            ``0 .. L_i``; ``L_i`` is the arrival time at its last goal.
        goal_times: Per agent ``int64 [G_i]`` arrival time of each goal, in order.
        expanded: High-level nodes taken from the open list (1 when the first plan
            has no conflict).
    """

    paths: list[np.ndarray]
    goal_times: list[np.ndarray]
    expanded: int


@dataclass
class _Agent:
    """Static data of one agent: flat start, goal cells and heuristic rows."""

    start: int
    goals: list[int]
    h: list[list[int]]  # h[k][c]: distance to goal k plus the remaining goal chain


@dataclass
class _Constraints:
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
_Conflict = tuple[str, int, int, int, int, int]


@dataclass
class _Node:
    cost: int
    paths: list[list[int]]
    goal_times: list[list[int]]
    cons: list[_Constraints]


def _conflicts(paths: list[list[int]]) -> tuple[int, list[_Conflict]]:
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


class _OutOfBudget(Exception):
    """The low-level expansion budget of one CBS call is spent."""


def _low_level(
    agent: _Agent,
    cons: _Constraints,
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
        others: The other agents' current paths (flat cells), for conflict avoidance.
        neighbours: Cell -> traversable cells reachable in one step, itself included.
        n: Number of grid cells.
        deadline: ``time.perf_counter()`` value past which to give up.
        budget: ``[expansions left]`` for the whole CBS call, decremented here.

    Returns:
        ``(path, goal_times)`` in flat cells, or ``None`` when no path exists.

    Raises:
        PlanningTimeout: The deadline passed (re-raised by the caller with context).
        _OutOfBudget: The call's expansion budget is spent.
    """
    vcons, econs, after = cons.vertex, cons.edge, cons.after
    goals, hrows = agent.goals, agent.h
    num_goals = len(goals)
    last = num_goals - 1
    final = goals[last]
    # The final goal counts only once the agent may stay on it for good.
    last_final = max([cons.finish_after, *(v // n for v in vcons if v % n == final)])
    tcap = cons.latest + 1  # from here on nothing depends on time
    fmin = last_final + 1
    # Conflict avoidance table: vertex occupancy, reversed moves, parked agents.
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

    def advance(c: int, t: int, k: int) -> int:
        while k < last and c == goals[k]:
            k += 1
        if k == last and c == final and t > last_final:
            k = num_goals
        return k

    if budget[0] < 0:
        raise _OutOfBudget
    k0 = advance(agent.start, 0, 0)
    h0 = 0 if k0 == num_goals else hrows[k0][agent.start]
    best: dict[int, int] = {k0 * n + agent.start: 0}  # time 0, no conflicts
    heap: list[tuple[int, int, int, int, int, int]] = [(max(h0, fmin), 0, 0, agent.start, k0, -1)]
    nodes: list[tuple[int, int, int]] = []  # expanded (cell, goal index, parent)
    expansions = 0
    span = num_goals + 1
    while heap:
        _, conf, neg_t, c, k, parent = heapq.heappop(heap)
        t = -neg_t
        key = ((t if t < tcap else tcap) * span + k) * n + c
        if best.get(key) != t * _CONF_SPAN + conf:
            continue  # stale or already expanded
        best[key] = -1
        nodes.append((c, k, parent))
        if k == num_goals:
            budget[0] -= expansions % _CHECK_EVERY
            return _reconstruct(nodes, num_goals)
        expansions += 1
        if expansions % _CHECK_EVERY == 0:
            if time.perf_counter() > deadline:
                raise PlanningTimeout("low-level search ran past its time limit")
            budget[0] -= _CHECK_EVERY
            if budget[0] < 0:
                raise _OutOfBudget
        me = len(nodes) - 1
        t1 = t + 1
        base_v = t1 * n
        base_e = (t * n + c) * n
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
    budget[0] -= expansions % _CHECK_EVERY
    return None


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


def cbs_solve(
    free: np.ndarray,
    blocked: np.ndarray,
    starts: np.ndarray,
    goals: Sequence[np.ndarray],
    heuristic: Callable[[int, int], np.ndarray],
    deadline: float,
    max_nodes: int | None = None,
    max_expansions: int | None = None,
) -> CBSSolution | None:
    """Plan conflict-free paths minimising the sum of arrival times at the last goals.

    Args:
        free: ``bool [H, W]``; ``True`` marks a traversable grid cell.
        blocked: ``bool [H, W]`` cells occupied forever (parked robots), extra obstacles.
        starts: ``int64 [A, 2]`` start cells ``(x, y)`` at relative time 0.
        goals: Per agent ``int64 [G_i, 2]`` goal cells (``G_i >= 1``), visited in order.
        heuristic: ``(x, y)`` of a goal -> ``int32 [H, W]`` 4-connected distances to it
            on ``free`` (ignoring ``blocked``), ``-1`` where unreachable.
        deadline: ``time.perf_counter()`` value past which to give up.
        max_nodes: High-level nodes to expand at most; past it the search gives up and
            returns ``None`` (a deterministic budget, unlike the deadline).
        max_expansions: Low-level A* expansions over the whole call at most (counted in
            steps of a few hundred); past it the search gives up and returns ``None``.

    Returns:
        An optimal :class:`CBSSolution`, or ``None`` when the instance is infeasible
        (a start or goal not traversable, a goal unreachable, two agents sharing a
        start or a final goal, or no plan found once the constraint tree is exhausted)
        or a budget (``max_nodes``, ``max_expansions``) was spent without a solution.

    Raises:
        PlanningTimeout: The search ran past ``deadline``.
    """
    try:
        return _cbs(free, blocked, starts, goals, heuristic, deadline, max_nodes, max_expansions)
    except _OutOfBudget:
        return None


def _cbs(
    free: np.ndarray,
    blocked: np.ndarray,
    starts: np.ndarray,
    goals: Sequence[np.ndarray],
    heuristic: Callable[[int, int], np.ndarray],
    deadline: float,
    max_nodes: int | None,
    max_expansions: int | None,
) -> CBSSolution | None:
    height, width = free.shape
    n = height * width
    ok = (np.asarray(free, dtype=bool) & ~np.asarray(blocked, dtype=bool)).ravel().tolist()
    starts = np.asarray(starts, dtype=np.int64).reshape(-1, 2)
    flat_starts = (starts[:, 1] * width + starts[:, 0]).tolist()
    if len(set(flat_starts)) < len(flat_starts) or not all(ok[s] for s in flat_starts):
        return None
    agents: list[_Agent] = []
    finals: set[int] = set()
    for s, g in zip(flat_starts, goals, strict=True):
        g = np.asarray(g, dtype=np.int64).reshape(-1, 2)
        cells = (g[:, 1] * width + g[:, 0]).tolist()
        if not cells or not all(ok[c] for c in cells) or cells[-1] in finals:
            return None
        finals.add(cells[-1])
        fields = [np.asarray(heuristic(int(x), int(y))).ravel() for x, y in g.tolist()]
        legs = [int(fields[0][s])] + [int(fields[k + 1][cells[k]]) for k in range(len(cells) - 1)]
        if min(legs) < 0:
            return None
        suffix = [sum(legs[k + 1 :]) for k in range(len(cells))]  # chain after goal k
        hrows = [(f.astype(np.int64) + sk).tolist() for f, sk in zip(fields, suffix, strict=True)]
        agents.append(_Agent(s, cells, hrows))

    nbr_cache: dict[int, list[int]] = {}

    def neighbours(c: int) -> list[int]:
        out = nbr_cache.get(c)
        if out is None:
            x = c % width
            out = [c]
            if x + 1 < width and ok[c + 1]:
                out.append(c + 1)
            if x > 0 and ok[c - 1]:
                out.append(c - 1)
            if c + width < n and ok[c + width]:
                out.append(c + width)
            if c >= width and ok[c - width]:
                out.append(c - width)
            nbr_cache[c] = out
        return out

    expanded = 0
    budget = [max_expansions if max_expansions is not None else 1 << 62]

    def plan(
        i: int, cons: _Constraints, paths: list[list[int]]
    ) -> tuple[list[int], list[int]] | None:
        others = paths[:i] + paths[i + 1 :]
        try:
            return _low_level(agents[i], cons, others, neighbours, n, deadline, budget)
        except PlanningTimeout:
            raise PlanningTimeout(
                f"CBS ran past its time limit after {expanded} high-level nodes"
            ) from None

    if time.perf_counter() > deadline:
        raise PlanningTimeout(f"CBS ran past its time limit after {expanded} high-level nodes")
    root_cons = [_Constraints() for _ in agents]
    paths: list[list[int]] = []
    goal_times: list[list[int]] = []
    for i in range(len(agents)):
        res = plan(i, root_cons[i], paths)  # avoid the agents planned so far
        if res is None:
            return None
        paths.append(res[0])
        goal_times.append(res[1])
    seen: set[tuple] = set()
    root = _Node(sum(len(p) - 1 for p in paths), paths, goal_times, root_cons)
    count, conflicts = _conflicts(paths)
    tie = 0
    open_list: list[tuple[int, int, int, _Node, list[_Conflict]]] = [
        (root.cost, count, tie, root, conflicts)
    ]
    while open_list:
        if time.perf_counter() > deadline:
            raise PlanningTimeout(f"CBS ran past its time limit after {expanded} high-level nodes")
        if max_nodes is not None and expanded >= max_nodes:
            return None
        _, count, _, node, conflicts = heapq.heappop(open_list)
        expanded += 1
        while conflicts:
            # Prefer a cardinal conflict (both children cost more), then a semi-cardinal
            # one, among the earliest few; adopt any same-cost child with fewer conflicts.
            best: tuple[int, list[tuple[int, int, int, _Node, list[_Conflict]]]] | None = None
            bypassed = False
            for conflict in conflicts[:_CANDIDATES]:
                children = []
                for agent, cons in _split(conflict, node.paths, node.cons, n):
                    res = plan(agent, cons, node.paths)
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
                        count, conflicts = child_count, child_conflicts
                        bypassed = True
                        break
                    all_cons = list(node.cons)
                    all_cons[agent] = cons
                    tie += 1
                    child = _Node(cost, paths, goal_times, all_cons)
                    children.append((cost, child_count, tie, child, child_conflicts))
                if bypassed:
                    break
                rank = 2 - sum(entry[0] > node.cost for entry in children) - (2 - len(children))
                if best is None or rank < best[0]:
                    best = (rank, children)
                if rank == 0:
                    break
            if not bypassed:
                break
        if not conflicts:
            return _solution(node, width, expanded)
        assert best is not None
        for entry in best[1]:
            # Skip a child whose constraint set is already in the tree (reached in
            # another order): the first copy covers the same solutions.
            signature = tuple(
                (c.vertex, c.edge, frozenset(c.after.items()), c.finish_after)
                for c in entry[3].cons
            )
            if signature not in seen:
                seen.add(signature)
                heapq.heappush(open_list, entry)
    return None


def _split(
    conflict: _Conflict, paths: list[list[int]], cons: list[_Constraints], n: int
) -> list[tuple[int, _Constraints]]:
    """The two ``(agent, new constraints)`` children of a conflict (see the module doc).

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


def _solution(node: _Node, width: int, expanded: int) -> CBSSolution:
    """Convert a conflict-free node's flat paths to ``(x, y)`` arrays."""
    paths = []
    for p in node.paths:
        flat = np.asarray(p, dtype=np.int64)
        paths.append(np.stack([flat % width, flat // width], axis=1))
    goal_times = [np.asarray(g, dtype=np.int64) for g in node.goal_times]
    return CBSSolution(paths=paths, goal_times=goal_times, expanded=expanded)
