"""Compiled kernel of the acting robot's rivals: the ``k`` robots arriving first at each
queued task, found in one pass over the fleet.

The NumPy form (:func:`rtaw_marl.decision.relational._rival_order`) builds the ``[P, N, M]``
arrival tensor, masks the actor and partitions it: at ``M = 1000`` that was most of a
batched env step. This kernel keeps a sorted list of ``k`` per task while it scans the
robots, so it reads each distance once and allocates nothing of size ``M``. Same float
operations (``(distance + remaining) - own``), same tie rule (the lowest robot id first),
so its results equal the NumPy form's bit for bit.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["first_rivals"]


@njit(cache=True, nogil=True)
def first_rivals(
    dist: np.ndarray, rem: np.ndarray, who: np.ndarray, k: int, order: np.ndarray, delta: np.ndarray
) -> None:
    """Each task's ``k`` first rivals of the acting robot, by ``arrival - own arrival``.

    Args:
        dist: ``float64 [P, M, N]`` distance from each robot's free cell to each origin.
        rem: ``float64 [P, M]`` time until each robot is free, clipped at 0.
        who: ``int64 [P]`` the acting robot of each of the ``P`` decisions.
        k: Rivals per task, ``1 <= k <= M - 1``.
        order: ``int64 [P, N, k]``, overwritten: rival robot ids, first arrival first.
        delta: ``float64 [P, N, k]``, overwritten: their arrival minus the actor's.
    """
    p_count, m, n = dist.shape
    own = np.empty(n)
    filled = np.empty(n, np.int64)
    for p in range(p_count):
        actor = who[p]
        for t in range(n):
            own[t] = dist[p, actor, t] + rem[p, actor]
            filled[t] = 0
        # Robots outer, tasks inner: the distances are read in memory order.
        for r in range(m):
            if r == actor:
                continue
            for t in range(n):
                value = (dist[p, r, t] + rem[p, r]) - own[t]
                f = filled[t]
                if f == k and value >= delta[p, t, k - 1]:
                    continue
                # Insert after every equal value: ties keep the lower robot id first.
                i = f if f < k else k - 1
                while i > 0 and delta[p, t, i - 1] > value:
                    delta[p, t, i] = delta[p, t, i - 1]
                    order[p, t, i] = order[p, t, i - 1]
                    i -= 1
                delta[p, t, i] = value
                order[p, t, i] = r
                if f < k:
                    filled[t] = f + 1


@njit(cache=True, nogil=True)
def actor_relations(
    dist: np.ndarray,
    free_at: np.ndarray,
    time: np.ndarray,
    who: np.ndarray,
    lengths: np.ndarray,
    waits: np.ndarray,
    nearest: np.ndarray,
    mask: np.ndarray,
    scale: float,
    k: int,
    missing: float,
    temperature: float,
    rel: np.ndarray,
    rivals: np.ndarray,
) -> None:
    """The acting robot's whole relational view, fused (no ``[P, N, M]`` temporaries).

    The compiled twin of the NumPy expressions of
    :func:`rtaw_marl.decision.features.relational_features` for one view: rivals by
    :func:`first_rivals`, then each task's 8 relations and ``K`` rival tokens.

    Args:
        dist: ``float64 [P, M, N]``; free_at: ``float64 [P, M]`` when each robot is
            free; time: ``float64 [P]`` the decisions' times (each robot's time until
            free is ``max(free_at - time, 0)``); who: ``int64 [P]``; lengths, waits:
            ``float64 [P, N]``; nearest: ``float64 [P, N]`` (``inf``: no other task);
            mask: ``bool [P, N]``.
        scale: ``L``. k: rivals kept (``min(K, M - 1)``). missing: the value of a missing
            rival or chain, in cells (``MISSING * L``). temperature: the soft-min's, in
            cells.
        rel: ``float32 [P, N, 8]``, overwritten. rivals: ``float32 [P, N, K, 4]``,
            overwritten (rows past ``k`` and of empty slots zero).
    """
    p_count, m, n = dist.shape
    rem = np.empty((p_count, m))
    for p in range(p_count):
        for r in range(m):
            rem[p, r] = max(free_at[p, r] - time[p], 0.0)
    order = np.zeros((p_count, n, max(k, 1)), np.int64)
    delta = np.zeros((p_count, n, max(k, 1)))
    if k:
        first_rivals(dist, rem, who, k, order, delta)
    rel[:] = 0.0
    rivals[:] = 0.0
    for p in range(p_count):
        actor = who[p]
        for t in range(n):
            if not mask[p, t]:
                continue
            row = np.empty(8)
            row[0] = dist[p, actor, t] + rem[p, actor]
            row[1] = lengths[p, t]
            row[2] = waits[p, t]
            row[3] = missing
            row[4] = missing
            row[5] = missing
            row[6] = missing
            row[7] = nearest[p, t] if nearest[p, t] < np.inf else missing
            if k:
                low = delta[p, t, 0]
                total = 0.0
                for i in range(k):
                    total += np.exp(-(delta[p, t, i] - low) / temperature)
                    if i < 3:
                        row[3 + i] = delta[p, t, i]
                    r = order[p, t, i]
                    rivals[p, t, i, 0] = delta[p, t, i] / scale
                    rivals[p, t, i, 1] = rem[p, r] / scale
                    rivals[p, t, i, 2] = dist[p, r, t] / scale
                    rivals[p, t, i, 3] = 1.0
                row[6] = low - temperature * np.log(total)
            for c in range(8):
                rel[p, t, c] = row[c] / scale
