"""Compiled kernel of the acting robot's rivals: the ``k`` robots arriving first at each
queued task, found in one pass over the fleet.

The NumPy form (:func:`rtaw_marl.envs.features._rival_order`) builds the ``[P, N, M]``
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
