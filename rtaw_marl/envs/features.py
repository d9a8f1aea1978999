"""Observation features, shared by every env adapter and by the evaluation policies.

Both the PettingZoo env and the batched TorchRL env call these functions, so the two
produce bit-identical observations. They work on one simulator's arrays or on stacked
``[B, ...]`` arrays alike. Lengths and times are divided by the layout scale
``L = max(W, H)`` (computed in float64, stored as float32).

Two feature sets are produced side by side:

* the paper's coordinates (``robots``, ``tasks``, ``agent``), read by ``model=rtaw``;
* relational features (``relations``, ``rivals``), read by ``model=rtaw_plus``: what the
  paper's network would have to learn from coordinates, computed with the navigator's
  distances. A robot's *arrival* at a task is its time until free plus the distance from
  the cell where it will be free to the task's origin; the acting robot is free now, so
  its arrival is its distance ``k``. *Rivals* are the other robots, ranked by arrival.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from rtaw_marl.sim.core import WarehouseSim

__all__ = [
    "MISSING",
    "NUM_RIVALS",
    "OBSERVATION_KEYS",
    "RELATIONAL_KEYS",
    "RELATION_FEATURES",
    "RIVAL_FEATURES",
    "ROBOT_FEATURES",
    "SOFTMIN_TEMPERATURE",
    "TASK_FEATURES",
    "all_relational_features",
    "relational_features",
    "robot_features",
    "sim_observation",
    "sim_relations",
    "task_features",
]

#: Observation keys of the free robot's decision, in the networks' argument order.
OBSERVATION_KEYS = ("robots", "tasks", "agent", "action_mask")
#: Keys of the relational features (``model=rtaw_plus``).
RELATIONAL_KEYS = ("relations", "rivals")
#: Columns of the robot features.
ROBOT_FEATURES = ("x", "y", "time_until_free")
#: Columns of the task features.
TASK_FEATURES = ("ox", "oy", "dx", "dy", "distance_to_origin", "length")
#: Columns of the relational task features (``relations``); all divided by ``L``.
RELATION_FEATURES = (
    "distance",  # k: the acting robot's distance to the origin
    "length",  # origin -> destination
    "wait",  # time the task has waited in the queue
    "rival_1",  # arrival of the fastest rival minus k
    "rival_2",
    "rival_3",
    "rival_softmin",  # soft-min over all rivals' arrivals, minus k
    "chain",  # distance from this task's destination to the nearest other queued origin
)
#: Columns of one rival token (``rivals [N, NUM_RIVALS, 4]``).
RIVAL_FEATURES = ("arrival_minus_k", "time_until_free", "distance", "valid")
#: Rivals per task in ``rivals``: the ``NUM_RIVALS`` other robots arriving first.
NUM_RIVALS = 8
#: Value (in units of ``L``) of a rival or chain feature that does not exist (fewer than
#: 3 other robots, a single queued task): "two layouts away", beyond any real distance.
MISSING = 2.0
#: Temperature of the rivals' soft-min, in units of ``L``.
SOFTMIN_TEMPERATURE = 0.05


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


def relational_features(
    distances: np.ndarray,
    remaining: np.ndarray,
    robot: np.ndarray | int,
    lengths: np.ndarray,
    waits: np.ndarray,
    chain: np.ndarray,
    mask: np.ndarray,
    scale: float,
) -> tuple[np.ndarray, np.ndarray]:
    """Relational task features and rival tokens of the acting robot's decision.

    Args:
        distances: ``float [..., M, N]`` from each robot's (next free) cell to each origin.
        remaining: ``float [..., M]`` time until each robot is free (0 for the actor).
        robot: ``int [...]`` the acting robot.
        lengths: ``float [..., N]`` task lengths.
        waits: ``float [..., N]`` time each task has waited in the queue.
        chain: ``float [..., N, N]`` from each queued destination to each queued origin.
        mask: ``bool [..., N]`` which slots hold a task.
        scale: ``L``.

    Returns:
        ``relations float32 [..., N, 8]`` (:data:`RELATION_FEATURES`) and ``rivals
        float32 [..., N, NUM_RIVALS, 4]`` (:data:`RIVAL_FEATURES`, sorted by arrival,
        invalid rows zero); empty slots are all zeros.
    """
    m = distances.shape[-2]
    remaining = np.maximum(remaining, 0.0)
    arrival = np.swapaxes(distances + remaining[..., :, None], -1, -2)  # [..., N, M]
    actor = np.asarray(robot)[..., None, None]
    is_actor = np.arange(m) == actor  # [..., 1, M]
    own = np.take_along_axis(arrival, np.broadcast_to(actor, (*arrival.shape[:-1], 1)), -1)
    delta = np.where(is_actor, np.inf, arrival - own)  # rivals only: [..., N, M]
    k = min(NUM_RIVALS, m - 1)
    order = _first(delta, k)
    ranked = np.take_along_axis(delta, order, -1)  # [..., N, k]

    rel = np.zeros((*mask.shape, len(RELATION_FEATURES)), dtype=np.float64)
    rel[..., 0] = own[..., 0]
    rel[..., 1] = lengths
    rel[..., 2] = waits
    rel[..., 3:6] = MISSING * scale
    top = min(k, 3)
    rel[..., 3 : 3 + top] = ranked[..., :top]
    rel[..., 6] = _softmin(ranked, SOFTMIN_TEMPERATURE * scale) if k else MISSING * scale
    rel[..., 7] = _nearest_other(chain, mask, MISSING * scale)
    rel = np.where(mask[..., None], rel / scale, 0.0)

    rivals = np.zeros((*mask.shape, NUM_RIVALS, len(RIVAL_FEATURES)), dtype=np.float64)
    rivals[..., :k, 0] = ranked
    rivals[..., :k, 1] = np.take_along_axis(
        np.broadcast_to(remaining[..., None, :], arrival.shape), order, -1
    )
    rivals[..., :k, 2] = np.take_along_axis(np.swapaxes(distances, -1, -2), order, -1)
    rivals[..., :k, :3] /= scale
    rivals[..., :k, 3] = 1.0
    rivals = np.where(mask[..., None, None], rivals, 0.0)
    return rel.astype(np.float32), rivals.astype(np.float32)


def all_relational_features(
    distances: np.ndarray,
    remaining: np.ndarray,
    lengths: np.ndarray,
    waits: np.ndarray,
    chain: np.ndarray,
    mask: np.ndarray,
    scale: float,
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`relational_features` of every robot's view of one decision at once.

    A robot's rivals at a task are the other robots in order of arrival, so one ranking
    of all robots per task serves every view: robot ``r``'s ``k`` first rivals are the
    ``k + 1`` first arrivals less ``r`` (or the ``k`` first when ``r`` is not among
    them). That costs ``O(M N)`` per decision instead of ``O(M^2 N)`` for ``M`` calls of
    :func:`relational_features`. Values are the same float operations; only the order of
    rivals with exactly equal arrivals may differ.

    Args:
        distances: ``float [M, N]`` from each robot's (next free) cell to each origin.
        remaining: ``float [M]`` time until each robot is free.
        lengths: ``float [N]`` task lengths.
        waits: ``float [N]`` time each task has waited in the queue.
        chain: ``float [N, N]`` from each queued destination to each queued origin.
        mask: ``bool [N]`` which slots hold a task.
        scale: ``L``.

    Returns:
        ``relations float32 [M, N, 8]`` and ``rivals float32 [M, N, NUM_RIVALS, 4]``: row
        ``r`` is ``relational_features(..., robot=r, ...)``.
    """
    m, n = distances.shape
    remaining = np.maximum(remaining, 0.0)
    arrival = distances.T + remaining  # [N, M]
    own = arrival.T  # [M, N]: each robot's own arrival
    k = min(NUM_RIVALS, m - 1)
    rel = np.zeros((m, n, len(RELATION_FEATURES)), dtype=np.float64)
    rel[..., 0] = own
    rel[..., 1] = lengths
    rel[..., 2] = waits
    rel[..., 3:6] = MISSING * scale
    rel[..., 6] = MISSING * scale
    rel[..., 7] = _nearest_other(chain, mask, MISSING * scale)
    rivals = np.zeros((m, n, NUM_RIVALS, len(RIVAL_FEATURES)), dtype=np.float64)
    if k:
        top = _first(arrival, k + 1)  # [N, k + 1] robot ids, first arrival first
        is_self = top == np.arange(m)[:, None, None]  # [M, N, k + 1]
        keep = ~is_self
        # Exactly k kept per row: drop the robot itself, or else the (k + 1)-th arrival.
        keep[..., k] &= is_self.any(-1)
        order = np.broadcast_to(top, keep.shape)[keep].reshape(m, n, k)  # [M, N, k]
        task = np.arange(n)[:, None]
        ranked = arrival[task, order] - own[..., None]  # [M, N, k]
        top3 = min(k, 3)
        rel[..., 3 : 3 + top3] = ranked[..., :top3]
        rel[..., 6] = _softmin(ranked, SOFTMIN_TEMPERATURE * scale)
        rivals[..., :k, 0] = ranked
        rivals[..., :k, 1] = remaining[order]
        rivals[..., :k, 2] = distances.T[task, order]
        rivals[..., :k, :3] /= scale
        rivals[..., :k, 3] = 1.0
    rel = np.where(mask[:, None], rel / scale, 0.0)
    rivals = np.where(mask[:, None, None], rivals, 0.0)
    return rel.astype(np.float32), rivals.astype(np.float32)


def _first(values: np.ndarray, k: int) -> np.ndarray:
    """Indices of the ``k`` smallest entries of the last axis, in ascending order (ties:
    lowest index); a partial partition first, so the cost stays ``O(M)`` per task."""
    if k < values.shape[-1] - 1:
        part = np.sort(np.argpartition(values, k - 1, axis=-1)[..., :k], axis=-1)
        values_k = np.take_along_axis(values, part, -1)
        return np.take_along_axis(part, np.argsort(values_k, axis=-1, kind="stable"), -1)
    return np.argsort(values, axis=-1, kind="stable")[..., :k]


def _softmin(values: np.ndarray, temperature: float) -> np.ndarray:
    """``-T log sum exp(-v / T)`` over the last axis, stable: at most its minimum."""
    low = values.min(axis=-1)
    return low - temperature * np.log(np.exp(-(values - low[..., None]) / temperature).sum(-1))


def _nearest_other(chain: np.ndarray, mask: np.ndarray, missing: float) -> np.ndarray:
    """``[..., N]`` distance from each destination to the nearest *other* queued origin."""
    n = mask.shape[-1]
    other = mask[..., None, :] & ~np.eye(n, dtype=bool)
    d = np.where(other, chain, np.inf).min(axis=-1)
    return np.where(np.isfinite(d), d, missing)


def sim_relations(sim: WarehouseSim) -> tuple[np.ndarray, np.ndarray]:
    """:func:`relational_features` of a simulator's current decision (acting robot)."""
    return relational_features(
        sim.distance_matrix(),
        sim.robot_remaining(),
        sim.robot,
        sim.queue_length,
        sim.queue_waits(),
        sim.chain_distances(),
        sim.queue_mask,
        sim.layout.scale,
    )


def sim_observation(sim: WarehouseSim, keys: tuple[str, ...]) -> dict[str, np.ndarray]:
    """The acting robot's observation entries ``keys`` (as the envs give them),
    computing only what ``keys`` needs."""
    scale = sim.layout.scale
    obs = {"action_mask": sim.queue_mask.copy()}
    if {"robots", "agent"} & set(keys):
        obs["robots"] = robot_features(sim.robot_xy, sim.robot_free_at, sim.time, scale)
        obs["agent"] = np.ascontiguousarray(obs["robots"][sim.robot])
    if "tasks" in keys:
        obs["tasks"] = task_features(
            sim.queue_rows, sim.queue_length, sim.robot_distances(), sim.queue_mask, scale
        )
    if {"relations", "rivals"} & set(keys):
        obs["relations"], obs["rivals"] = sim_relations(sim)
    return obs
