"""Observation features of the paper's state, shared by every env adapter.

Both the PettingZoo env and the batched TorchRL env call these functions, so the two
produce bit-identical observations. They work on one simulator's arrays or on stacked
``[B, ...]`` arrays alike. Lengths and times are divided by the layout scale
``L = max(W, H)`` (computed in float64, stored as float32).
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "OBSERVATION_KEYS",
    "ROBOT_FEATURES",
    "TASK_FEATURES",
    "robot_features",
    "task_features",
]

#: Observation keys of the free robot's decision, in the networks' argument order.
OBSERVATION_KEYS = ("robots", "tasks", "agent", "action_mask")
#: Columns of the robot features.
ROBOT_FEATURES = ("x", "y", "time_until_free")
#: Columns of the task features.
TASK_FEATURES = ("ox", "oy", "dx", "dy", "distance_to_origin", "length")


def robot_features(
    robot_xy: np.ndarray, free_at: np.ndarray, time: np.ndarray | float, scale: float
) -> np.ndarray:
    """Robot rows ``(x, y, time_until_free) / L``.

    Args:
        robot_xy: ``int [..., M, 2]`` cells.
        free_at: ``float [..., M]`` free times.
        time: ``float [...]`` current decision time(s).
        scale: ``L``.

    Returns:
        ``float32 [..., M, 3]``.
    """
    out = np.empty((*free_at.shape, 3), dtype=np.float32)
    out[..., :2] = robot_xy / scale
    remaining = free_at - np.asarray(time, dtype=np.float64)[..., None]
    out[..., 2] = np.maximum(remaining, 0.0) / scale
    return out


def task_features(
    queue_rows: np.ndarray,
    queue_length: np.ndarray,
    distance: np.ndarray,
    mask: np.ndarray,
    scale: float,
) -> np.ndarray:
    """Task rows ``(ox, oy, dx, dy, k, l) / L``; rows of empty slots are zero.

    Args:
        queue_rows: ``int [..., N, 4]`` task cells per slot (zeros when empty).
        queue_length: ``float [..., N]`` task lengths (0 when empty).
        distance: ``float [..., N]`` distance from the observing robot to each origin.
        mask: ``bool [..., N]`` which slots hold a task.
        scale: ``L``.

    Returns:
        ``float32 [..., N, 6]``.
    """
    out = np.empty((*queue_length.shape, 6), dtype=np.float32)
    out[..., :4] = queue_rows / scale
    out[..., 4] = np.where(mask, distance, 0.0) / scale
    out[..., 5] = queue_length / scale
    return out
