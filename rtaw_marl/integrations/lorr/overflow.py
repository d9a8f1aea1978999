"""Robots the scheduler's clock cannot serve: wait, or take the nearest task.

Inside LoRR's time limit a scheduler serves the free robots it can; the rest wait for the
next timestep (``deferred``), as LoRR's default scheduler lets them. When every robot is
free at once (t = 0: 5,000 or 10,000 robots), a learned policy at a few milliseconds a
robot serves a few hundred per timestep, and the others wait for tens of timesteps.

``overflow=nearest`` hands them a task instead: each robot left when the policy's share
of the clock runs out takes the open task whose pickup is nearest it by grid (Manhattan)
distance, robots with the nearest pickups choosing first (:func:`nearest_pairs`). Grid
distance ignores the shelves, so these are a rule's choices, not the policy's: the run
counts them (``overflowed``). It costs a few milliseconds for thousands of robots (a
k-d tree query and one pass), so the policy keeps :data:`RESERVE` of the budget back.
"""

from __future__ import annotations

import numpy as np
from numba import njit
from scipy.spatial import cKDTree

from rtaw_marl.integrations.lorr.config import OVERFLOWS

__all__ = ["OVERFLOWS", "RESERVE", "nearest_pairs"]

#: The part of the scheduler's budget kept back for ``overflow=nearest``.
RESERVE = 0.1
#: Pickups considered per robot and round (a robot whose ``_K`` nearest went to others
#: chooses again among the tasks left).
_K = 32


def nearest_pairs(robot_xy: np.ndarray, task_xy: np.ndarray, k: int = _K) -> np.ndarray:
    """Each robot's task by grid distance, greedily: ``int64 [R]`` indices into
    ``task_xy``, ``-1`` only when there are fewer tasks than robots.

    Robots choose in the order of the distance to their nearest task (ties to the lower
    row), each taking its nearest task not yet taken among its ``k`` nearest, so a task
    goes to the robot nearest it among those that want it first. Robots whose ``k``
    nearest all went to others choose again, the same way, among the tasks left.

    Args:
        robot_xy: ``int [R, 2]`` the robots' cells.
        task_xy: ``int [T, 2]`` the tasks' pickup cells.
        k: Tasks considered per robot and round.
    """
    got = np.full(len(robot_xy), -1, dtype=np.int64)
    taken = np.zeros(len(task_xy), dtype=np.bool_)
    left = np.arange(len(robot_xy))
    while len(left) and not taken.all():
        free = np.flatnonzero(~taken)
        kk = min(int(k), len(free))
        dist, idx = cKDTree(np.asarray(task_xy, dtype=np.float64)[free]).query(
            np.asarray(robot_xy, dtype=np.float64)[left], k=kk, p=1
        )
        idx = free[np.asarray(idx, dtype=np.int64).reshape(len(left), kk)]
        first = np.asarray(dist, dtype=np.float64).reshape(len(left), kk)[:, 0]
        sub = np.full(len(left), -1, dtype=np.int64)
        # Each round serves at least its first robot: the loop ends.
        _take_nearest(idx, np.argsort(first, kind="stable"), taken, sub)
        got[left] = sub
        left = left[sub < 0]
    return got


@njit(cache=True, nogil=True)
def _take_nearest(idx: np.ndarray, order: np.ndarray, taken: np.ndarray, got: np.ndarray) -> None:
    for row in order:
        for j in range(idx.shape[1]):
            task = idx[row, j]
            if not taken[task]:
                taken[task] = True
                got[row] = task
                break
