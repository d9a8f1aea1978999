"""Greedy robot-task matching over all pairs: the 2024 LoRR winner's scheduler core.

The winning team's scheduler (``Straple/OMAPFS``, ``greedy_scheduler.cpp``) scores every
pair of a robot without a started task and a task not yet started by

    ``PAIR_WEIGHT x distance(robot's cell, task's first errand) + task's length``

and takes the cheapest pair again and again (a heap of each robot's sorted list), each
robot and task at most once. Here :func:`greedy_pairs` does the same on a cost matrix:
each robot's ``k`` cheapest tasks (``np.argpartition``), one compiled heap over those
lists, and, for the robots whose ``k`` tasks were all taken, another round over the
tasks left with ``4 k``. That is the exact greedy matching whenever no robot exhausts
its list before it is matched (a robot that does would, in the full greedy, compete for
its ``k + 1``-th task among the pairs of the same cost level; here it comes after them).

Ties are broken as the winner's heap does: by cost, then robot, then the task's rank in
the robot's list, then (within equal costs in one row) the lower task column.
"""

from __future__ import annotations

import heapq
from collections.abc import Mapping
from typing import Any

import numpy as np
from numba import njit

from rtaw_marl.sim.config import PAIR_WEIGHT
from rtaw_marl.sim.core import WarehouseSim

__all__ = ["PAIR_WEIGHT", "PairGreedy", "greedy_pairs", "pair_costs"]


def pair_costs(
    to_pickup: np.ndarray, length: np.ndarray, weight: float = PAIR_WEIGHT
) -> np.ndarray:
    """``weight x to_pickup [R, K] + length [K]``: the winner's cost of each pair."""
    return weight * to_pickup + length[None, :]


def greedy_pairs(cost: np.ndarray, k: int = 16) -> np.ndarray:
    """The task column taken by each row of ``cost [R, K]`` in the greedy matching
    (cheapest pair first, each row and column at most once), ``int64 [R]``, ``-1``
    for a row left without a task (more rows than columns).

    Args:
        cost: Finite pair costs.
        k: Columns per row sorted up front; a row whose ``k`` were all taken scans its
            row for the cheapest column left (so the result is exact for any ``k``).
    """
    cost = np.ascontiguousarray(cost, dtype=np.float64)
    rows, cols = cost.shape
    got = np.full(rows, -1, dtype=np.int64)
    if rows == 0 or cols == 0:
        return got
    kk = min(max(1, int(k)), cols)
    if kk < cols:
        cand = np.argpartition(cost, kk - 1, axis=1)[:, :kk]
        cand.sort(axis=1)  # column order first: equal costs then rank by column
    else:
        cand = np.broadcast_to(np.arange(cols), cost.shape).copy()
    vals = np.take_along_axis(cost, cand, axis=1)
    order = np.argsort(vals, axis=1, kind="stable")
    lists = np.ascontiguousarray(np.take_along_axis(cand, order, axis=1))
    vals = np.take_along_axis(vals, order, axis=1)
    # Ties at a truncated list's last cost may have left out a lower column of that
    # cost (argpartition picks any): trust the list below that cost, scan from there.
    trusted = np.full(rows, kk, dtype=np.int64)
    if kk < cols:
        trusted = (vals < vals[:, -1:]).sum(axis=1)
    _take(cost, lists, trusted, np.zeros(cols, dtype=np.bool_), got)
    return got


@njit(cache=True, nogil=True)
def _take(
    cost: np.ndarray, lists: np.ndarray, trusted: np.ndarray, taken: np.ndarray, got: np.ndarray
) -> None:
    """The winner's heap: pop the cheapest ``(cost, row, rank, column)``; take the column
    if free, else push the row's next candidate (from the first ``trusted[r]`` of
    ``lists [R, k]``, then from a scan of the row for the cheapest column not taken)."""
    rows = lists.shape[0]
    heap = [(0.0, 0, 0, 0)]
    heap.pop()
    for r in range(rows):
        heap.append(_next(cost, lists, trusted, taken, r, 0))
    heapq.heapify(heap)
    left = cost.shape[1]
    while len(heap) and left:
        _, r, i, col = heapq.heappop(heap)
        if col < 0:
            continue  # the row found no column left
        if not taken[col]:
            taken[col] = True
            got[r] = col
            left -= 1
            continue
        heapq.heappush(heap, _next(cost, lists, trusted, taken, r, i + 1))


@njit(cache=True, nogil=True)
def _next(
    cost: np.ndarray, lists: np.ndarray, trusted: np.ndarray, taken: np.ndarray, r: int, i: int
) -> tuple[float, int, int, int]:
    """Row ``r``'s candidate of rank ``i``: from its list while trusted, else the
    cheapest column not taken (lowest column on ties; rank ``k`` for all of those)."""
    if i < trusted[r]:
        col = lists[r, i]
        return (cost[r, col], r, i, col)
    best, col = np.inf, -1
    for c in range(cost.shape[1]):
        if not taken[c] and cost[r, c] < best:
            best, col = cost[r, c], c
    return (best, r, lists.shape[1], col)


class PairGreedy:
    """``pair_greedy``: the 2024 winner's scheduler in the own simulator.

    At the first decision of a timestep, the robots free now and the robots holding a
    reassignable task (``sim.reassign``: assigned, not yet picked up) are matched to the
    queued and reassignable tasks by :func:`greedy_pairs` on :func:`pair_costs`, from
    where each robot stands, as the winner's scheduler re-pairs every robot without a
    started task each timestep in LoRR's simulator: a holder matched to another task,
    or whose task went to another robot, gives its task back (``sim.release``) and
    decides in this timestep. Each deciding robot then takes its match; one left
    without a match takes its cheapest queued task. Without ``sim.reassign`` it matches
    the free robots to the queued tasks only.

    Acts on the simulator only (:meth:`act_sim`), like ``batch``: the matching needs
    every robot's position. Its choices are deterministic.

    Args:
        weight: Cost of a cell of travel to the pickup against one of the task's length.
    """

    name = "pair_greedy"

    def __init__(self, weight: float = PAIR_WEIGHT) -> None:
        self.weight = float(weight)
        self.reset()

    def reset(self, seed: int | None = None) -> None:
        """Forget the timestep's matching (the seed is unused: no random ties)."""
        del seed
        self._plan: tuple[tuple[int, float], dict[int, tuple[int, int]]] | None = None

    def act_sim(self, sim: WarehouseSim) -> int:
        if self._plan is not None and self._plan[0] == (id(sim), sim.time):
            planned = self._plan[1].get(sim.robot)
            if planned is not None:
                slot, task = planned
                if sim.queue_ids[slot] == task and sim.legal_actions()[slot]:
                    return slot
        return self._solve(sim)

    def _solve(self, sim: WarehouseSim) -> int:
        legal = sim.legal_actions()
        slots = np.flatnonzero(legal)
        free = sim.free_robots()
        held = np.flatnonzero(sim.reassignable())
        holders = sim.queue_holder[held]
        robots = np.concatenate([free, holders])
        cost = pair_costs(
            sim.distances_from(sim.robot_cells(robots), slots), sim.queue_length[slots],
            self.weight,
        )  # fmt: skip
        cols = greedy_pairs(cost)
        # A holder matched elsewhere, or whose task is matched to another robot, gives
        # its task back now and takes its match in this timestep (LoRR: every robot
        # without a started task is re-paired each timestep).
        own = np.searchsorted(slots, held)
        theirs = cols[len(free) :]
        taken = np.zeros(len(slots), dtype=bool)
        taken[cols[cols >= 0]] = True
        switch = (theirs != own) & ((theirs >= 0) | taken[own])
        if switch.any():
            sim.release(holders[switch])
        deciding = np.concatenate([free, holders[switch]])
        matched = np.concatenate([cols[: len(free)], theirs[switch]])
        plan = {
            int(r): (int(slots[c]), int(sim.queue_ids[slots[c]]))
            for r, c in zip(deciding.tolist(), matched.tolist(), strict=True)
            if c >= 0
        }
        self._plan = ((id(sim), sim.time), plan)
        if sim.robot in plan:
            return plan[sim.robot][0]
        me = int(np.searchsorted(free, sim.robot))
        queued = sim.queue_mask[slots]
        row = np.where(queued, cost[me], np.inf) if queued.any() else cost[me]
        return int(slots[int(np.argmin(row))])

    def act(self, observation: Mapping[str, Any]) -> int:
        """Not available: use :meth:`act_sim` (the matching needs every robot's position).

        Raises:
            NotImplementedError: Always.
        """
        raise NotImplementedError(
            "pair_greedy acts on the simulator only (it matches every robot at once); "
            "evaluate it with rtaw-eval or act_sim"
        )
