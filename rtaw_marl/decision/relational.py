"""Relational features of several robots' views of a decision, in NumPy.

Every robot's view at once (the PettingZoo env's other agents, TorchRL's
``PettingZooWrapper``) in ``O(M N + V N k)``; the acting robot's view alone goes to the
compiled kernel (:mod:`rtaw_marl.decision._rivals`), whose values these expressions
define.
"""

from __future__ import annotations

from math import prod

import numpy as np

from rtaw_marl.decision._rivals import actor_relations, first_rivals
from rtaw_marl.decision.schema import (
    MISSING,
    NUM_RIVALS,
    RELATION_FEATURES,
    RIVAL_FEATURES,
    SOFTMIN_TEMPERATURE,
)

__all__ = ["relational_features"]


def relational_features(
    distances: np.ndarray,
    remaining: np.ndarray,
    viewers: np.ndarray,
    lengths: np.ndarray,
    waits: np.ndarray,
    nearest: np.ndarray,
    mask: np.ndarray,
    scale: float,
) -> tuple[np.ndarray, np.ndarray]:
    """Relational task features and rival tokens of some robots' views of a decision.

    Each view is the one its robot would see as the acting robot: rivals ranked by
    ``arrival - own arrival``. ``V`` views cost ``O(M N + V N k)`` (one shared ranking;
    see :func:`_rival_order` for the one difference from ranking each view alone).

    Args:
        distances: ``float [..., M, N]`` from each robot's (next free) cell to each origin.
        remaining: ``float [..., M]`` time until each robot is free (0 for the actor).
        viewers: ``int [..., V]`` the robots whose views are computed.
        lengths: ``float [..., N]`` task lengths.
        waits: ``float [..., N]`` time each task has waited in the queue.
        nearest: ``float [..., N]`` from each queued destination to the nearest origin of
            another queued task (``inf``: none; the feature is then :data:`MISSING`).
        mask: ``bool [..., N]`` which slots hold a task.
        scale: ``L``.

    Returns:
        ``relations float32 [..., V, N, 8]`` (:data:`RELATION_FEATURES`) and ``rivals
        float32 [..., V, N, NUM_RIVALS, 4]`` (:data:`RIVAL_FEATURES`, sorted by arrival,
        invalid rows zero); empty slots are all zeros.
    """
    lead, (m, n) = distances.shape[:-2], distances.shape[-2:]
    p, v = prod(lead), np.shape(viewers)[-1]
    dist = distances.reshape(p, m, n)
    rem = np.maximum(remaining, 0.0).reshape(p, m)
    who = np.broadcast_to(viewers, (*lead, v)).reshape(p, v)
    pi = np.arange(p)[:, None, None]
    k = min(NUM_RIVALS, m - 1)
    shape = (*lead, v, n)
    if v == 1:
        # The acting robot alone (every env step): one compiled pass, no [P, N, M] arrays.
        rel32 = np.empty((p, n, len(RELATION_FEATURES)), dtype=np.float32)
        rivals32 = np.empty((p, n, NUM_RIVALS, len(RIVAL_FEATURES)), dtype=np.float32)
        actor_relations(
            np.ascontiguousarray(dist, dtype=np.float64),
            np.ascontiguousarray(remaining, dtype=np.float64).reshape(p, m), np.zeros(p),
            np.ascontiguousarray(who[:, 0], dtype=np.int64),
            np.ascontiguousarray(lengths, dtype=np.float64).reshape(p, n),
            np.ascontiguousarray(waits, dtype=np.float64).reshape(p, n),
            np.ascontiguousarray(nearest, dtype=np.float64).reshape(p, n),
            np.ascontiguousarray(mask, dtype=np.bool_).reshape(p, n), float(scale), k,
            MISSING * scale, SOFTMIN_TEMPERATURE * scale, rel32, rivals32,
        )  # fmt: skip
        return (
            rel32.reshape(*shape, len(RELATION_FEATURES)),
            rivals32.reshape(*shape, NUM_RIVALS, len(RIVAL_FEATURES)),
        )
    arrival = np.swapaxes(dist + rem[:, :, None], -1, -2)  # [P, N, M]
    task = np.arange(n)[None, :, None]
    own = np.swapaxes(arrival[pi, task, who[:, None, :]], -1, -2)  # [P, V, N]
    if k:
        order = _rival_order(arrival, own, who, k)  # [P, V, N, k] robot ids
        tk = np.arange(n)[None, None, :, None]
        ranked = arrival[pi[..., None], tk, order] - own[..., None]  # [P, V, N, k]

    rel = np.zeros((p, v, n, len(RELATION_FEATURES)), dtype=np.float64)
    rel[..., 0] = own
    rel[..., 1] = lengths.reshape(p, 1, n)
    rel[..., 2] = waits.reshape(p, 1, n)
    rel[..., 3:7] = MISSING * scale
    near = np.asarray(nearest, dtype=np.float64).reshape(p, 1, n)
    rel[..., 7] = np.where(np.isfinite(near), near, MISSING * scale)
    rivals = np.zeros((p, v, n, NUM_RIVALS, len(RIVAL_FEATURES)), dtype=np.float64)
    if k:
        pk, tk = pi[..., None], np.arange(n)[None, None, :, None]
        top = min(k, 3)
        rel[..., 3 : 3 + top] = ranked[..., :top]
        rel[..., 6] = _softmin(ranked, SOFTMIN_TEMPERATURE * scale)
        rivals[..., :k, 0] = ranked
        rivals[..., :k, 1] = rem[pk, order]
        rivals[..., :k, 2] = dist[pk, order, tk]
        rivals[..., :k, :3] /= scale
        rivals[..., :k, 3] = 1.0
    live = mask.reshape(p, 1, n)
    rel = np.where(live[..., None], rel / scale, 0.0)
    rivals = np.where(live[..., None, None], rivals, 0.0)
    return (
        rel.astype(np.float32).reshape(*shape, len(RELATION_FEATURES)),
        rivals.astype(np.float32).reshape(*shape, NUM_RIVALS, len(RIVAL_FEATURES)),
    )


def _actor_rivals(
    dist: np.ndarray, rem: np.ndarray, actor: np.ndarray, k: int
) -> tuple[np.ndarray, np.ndarray]:
    """The acting robot's ``k`` first rivals at each task (:func:`first_rivals`):
    ``order int [P, 1, N, k]`` and ``arrival - own float64 [P, 1, N, k]``."""
    p, _, n = dist.shape
    order = np.zeros((p, n, max(k, 1)), dtype=np.int64)
    delta = np.zeros((p, n, max(k, 1)), dtype=np.float64)
    if k:
        first_rivals(
            np.ascontiguousarray(dist, dtype=np.float64), np.ascontiguousarray(rem),
            np.ascontiguousarray(actor, dtype=np.int64), k, order, delta,
        )  # fmt: skip
    return order[:, None, :, :k], delta[:, None, :, :k]


def _rival_order(arrival: np.ndarray, own: np.ndarray, who: np.ndarray, k: int) -> np.ndarray:
    """``int [P, V, N, k]``: each view's ``k`` first rivals at each task (``arrival
    [P, N, M]``, ``own [P, V, N]``, ``who [P, V]``).

    Several views (the acting robot's alone take :func:`_actor_rivals`'s compiled path)
    share one ranking of all robots by arrival: robot ``r``'s ``k`` first rivals are the
    ``k + 1`` first arrivals less
    ``r`` (or the ``k`` first when ``r`` is not among them), ``O(M N)`` instead of
    ``O(V M N)``. The values are the same float operations; only rivals with exactly
    equal arrivals at the ``k``-th place may be chosen or ordered differently, so a
    caller that needs the acting row exactly asks for it alone.
    """
    top = _first(arrival, k + 1)  # [P, N, k + 1] robot ids, first arrival first
    is_self = top[:, None] == who[:, :, None, None]  # [P, V, N, k + 1]
    keep = ~is_self
    # Exactly k kept per row: drop the robot itself, or else the (k + 1)-th arrival.
    keep[..., k] &= is_self.any(-1)
    return np.broadcast_to(top[:, None], keep.shape)[keep].reshape(*keep.shape[:-1], k)


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
