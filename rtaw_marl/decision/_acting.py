"""Compiled kernel of the acting robot's coordinate entries (``robots``, ``agent``,
``tasks``); its relational ones are :func:`~rtaw_marl.decision._rivals.actor_relations`.

:func:`~rtaw_marl.decision.features.decision_features` builds the acting robot's view
on every env step. In NumPy that is some thirty small array operations whose overhead,
not their arithmetic, was most of an AEC step at ``M = 100`` (34 us of 110). This
kernel and the relational one write every entry in one pass with the same float
operations in the same order (``float64`` arithmetic, one rounding to ``float32`` at
the end), so their output equals the NumPy form's bit for bit; the tests compare the
two on batches of decisions.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["acting_features"]


@njit(cache=True, nogil=True)
def acting_features(
    robot_xy: np.ndarray,
    free_at: np.ndarray,
    time: np.ndarray,
    robot: np.ndarray,
    rows: np.ndarray,
    lengths: np.ndarray,
    mask: np.ndarray,
    scale: float,
    own: np.ndarray,
    robots: np.ndarray,
    agent: np.ndarray,
    tasks: np.ndarray,
) -> None:
    """The coordinate entries of ``P`` decisions' acting views.

    Args:
        robot_xy: ``int64 [P, M, 2]``; free_at: ``float64 [P, M]``; time: ``float64
            [P]``; robot: ``int64 [P]`` the acting robots.
        rows: ``int64 [P, N, 4]``; lengths: ``float64 [P, N]``; mask: ``bool [P, N]``.
        scale: ``L``.
        own: ``float64 [P, N]`` the acting robot's distance to each origin (read only
            when ``tasks`` has rows).
        robots: ``float32 [P, M, 3]`` (or ``[P, 0, 3]``: not wanted), overwritten.
        agent: ``float32 [P, 3]`` (or ``[0, 3]``), overwritten.
        tasks: ``float32 [P, N, 6]`` (or ``[0, N, 6]``), overwritten.
    """
    p_count, m = free_at.shape
    n = mask.shape[1]
    want_robots, want_agent = robots.shape[1] > 0, agent.shape[0] > 0
    want_tasks = tasks.shape[0] > 0
    for p in range(p_count):
        if want_robots:
            for r in range(m):
                robots[p, r, 0] = robot_xy[p, r, 0] / scale
                robots[p, r, 1] = robot_xy[p, r, 1] / scale
                robots[p, r, 2] = max(free_at[p, r] - time[p], 0.0) / scale
        if want_agent:
            a = robot[p]
            agent[p, 0] = robot_xy[p, a, 0] / scale
            agent[p, 1] = robot_xy[p, a, 1] / scale
            agent[p, 2] = max(free_at[p, a] - time[p], 0.0) / scale
        if want_tasks:
            for t in range(n):
                for c in range(4):
                    tasks[p, t, c] = rows[p, t, c] / scale
                tasks[p, t, 4] = (own[p, t] if mask[p, t] else 0.0) / scale
                tasks[p, t, 5] = lengths[p, t] / scale
