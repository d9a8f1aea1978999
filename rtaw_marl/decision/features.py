"""The observation of a decision: ONE builder, shared by every env adapter and policy.

:func:`decision_features` computes the acting robot's features (or several robots'
views at once) from a :class:`Decision`, the arrays of one simulator or of a batch of
``B`` simulators stacked as ``[B, ...]``. The PettingZoo env (every agent's view), the
Gymnasium env, the batched TorchRL env and the policies' ``act_sim`` fast path all call
it, so their observations are bit-identical by construction. Lengths and times are
divided by the layout scale ``L = max(W, H)`` (computed in float64, stored as float32);
the action mask is ``bool`` here (the PettingZoo and Gymnasium adapters hand it out as
``int8``, their libraries' convention). :func:`feature_shapes` is the one place shapes
are written.

Two feature sets are produced side by side:

* the paper's coordinates (``robots``, ``tasks``, ``agent``), read by ``model=rtaw``;
* relational features (``relations``, ``rivals``), read by ``model=rtaw_plus``: what the
  paper's network would have to learn from coordinates, computed with the distance model's
  distances. A robot's *arrival* at a task is its time until free plus the distance from
  the cell where it will be free to the task's origin; the acting robot is free now, so
  its arrival is its distance ``k``. *Rivals* are the other robots, ranked by arrival
  minus ``k`` (ties: the lowest robot id).
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import TYPE_CHECKING

import numpy as np

from rtaw_marl.decision.acting import acting_view, sim_acting_view
from rtaw_marl.decision.relational import relational_features
from rtaw_marl.decision.schema import (
    ALL_KEYS,
    FEATURES,
    FLEET_FEATURES,
    FLEET_QUANTILES,
    MISSING,
    NUM_RIVALS,
    OBSERVATION_KEYS,
    RELATION_FEATURES,
    RELATIONAL_KEYS,
    RIVAL_FEATURES,
    ROBOT_FEATURES,
    SOFTMIN_TEMPERATURE,
    TASK_FEATURES,
    Decision,
    feature_shapes,
)

if TYPE_CHECKING:
    from rtaw_marl.sim.core import WarehouseSim

__all__ = [
    "ALL_KEYS",
    "FEATURES",
    "FLEET_FEATURES",
    "FLEET_QUANTILES",
    "MISSING",
    "NUM_RIVALS",
    "OBSERVATION_KEYS",
    "RELATIONAL_KEYS",
    "RELATION_FEATURES",
    "RIVAL_FEATURES",
    "ROBOT_FEATURES",
    "SOFTMIN_TEMPERATURE",
    "TASK_FEATURES",
    "Decision",
    "candidate_slots",
    "decision_features",
    "feature_shapes",
    "fleet_features",
    "nearest_other",
    "relational_features",
    "robot_features",
    "sim_observation",
    "sim_relations",
    "task_features",
]


def decision_features(
    decision: Decision,
    keys: Iterable[str],
    viewers: np.ndarray | None = None,
    columns: np.ndarray | None = None,
) -> dict[str, np.ndarray]:
    """The observation entries ``keys`` of a decision, computing only what they need.

    Args:
        decision: The decision's arrays.
        keys: Feature keys (:data:`ALL_KEYS`); ``action_mask`` is always included.
        viewers: ``None``: the acting robot's view. ``int [V]`` (one simulator): the
            views of these robots, as each would see the decision if it were acting.
        columns: With ``viewers``, ``int [V, C]``: the decision's slots each view holds
            (its candidates), so the per-task entries are ``[V, C, ...]`` and cost
            ``O(V C)``, not ``O(V N)``; the mask is then ``bool [V, C]``.

    Returns:
        ``{key: array}``: float32 ``[..., *feature_shapes()[key]]`` (``[V, ...]`` with
        ``viewers``; ``robots`` is then a read-only broadcast of the one table) and
        ``action_mask`` ``bool [..., N]`` (a copy; with ``viewers``, the acting robot's).
    """
    keys, d = set(keys), decision
    if columns is not None:
        if viewers is None:
            raise ValueError("decision_features: columns need viewers")
        return _column_views(d, keys, np.asarray(viewers), np.asarray(columns, np.int64))
    if viewers is None:
        out = acting_view(d, keys)
        if "fleet" in keys:
            out["fleet"] = fleet_features(d.free_at, d.time, d.scale)
        return out
    viewers = np.asarray(viewers)
    out = _fleet_views(d, keys, viewers)
    out["action_mask"] = np.array(d.queue_mask, dtype=bool)
    if "tasks" in keys:
        own = d.distances[viewers]
        out["tasks"] = task_features(d.queue_rows, d.queue_length, own, d.queue_mask, d.scale)
    if set(RELATIONAL_KEYS) & keys:
        remaining = d.free_at - np.asarray(d.time, dtype=np.float64)[..., None]
        out["relations"], out["rivals"] = relational_features(
            d.distances, remaining, viewers, d.queue_length, d.waits, d.nearest, d.queue_mask,
            d.scale,
        )  # fmt: skip
    return out


def _column_views(
    d: Decision, keys: set[str], viewers: np.ndarray, columns: np.ndarray
) -> dict[str, np.ndarray]:
    """:func:`decision_features` of ``viewers [V]``, each over its ``columns [V, C]``."""
    out = _fleet_views(d, keys, viewers)
    out["action_mask"] = np.asarray(d.queue_mask, dtype=bool)[columns]
    if "tasks" in keys:
        own = np.take_along_axis(d.distances[viewers], columns, axis=1)
        out["tasks"] = task_features(
            d.queue_rows[columns], d.queue_length[columns], own, out["action_mask"], d.scale
        )
    if set(RELATIONAL_KEYS) & keys:
        out["relations"], out["rivals"] = _column_relations(d, viewers, columns)
    return out


#: Views per pass of :func:`_column_relations`: bounds its ``[V, M, C]`` distances.
_VIEW_CHUNK = 64


def _column_relations(
    d: Decision, viewers: np.ndarray, columns: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """``relations [V, C, 8]`` and ``rivals [V, C, K, 4]`` of each view over its columns:
    each view is a decision of its own (its columns' distances for the whole fleet), so
    the compiled acting path serves them all, bit for bit the acting robot's view."""
    remaining = d.free_at - np.asarray(d.time, dtype=np.float64)
    rel, rivals = [], []
    for start in range(0, len(viewers), _VIEW_CHUNK):
        who, cols = viewers[start : start + _VIEW_CHUNK], columns[start : start + _VIEW_CHUNK]
        dist = np.ascontiguousarray(np.moveaxis(d.distances[:, cols], 0, 1))  # [V, M, C]
        r, k = relational_features(
            dist, np.broadcast_to(remaining, (len(who), len(remaining))), who[:, None],
            d.queue_length[cols], d.waits[cols], d.nearest[cols], d.queue_mask[cols], d.scale,
        )  # fmt: skip
        rel.append(r[:, 0])
        rivals.append(k[:, 0])
    return np.concatenate(rel), np.concatenate(rivals)


def _fleet_views(d: Decision, keys: set[str], viewers: np.ndarray) -> dict[str, np.ndarray]:
    """The entries of ``viewers [V]``'s views without a task axis (``robots``, ``agent``,
    ``fleet``)."""
    out = {}
    if {"robots", "agent"} & keys:
        rows = robot_features(d.robot_xy, d.free_at, d.time, d.scale)
        out["robots"] = np.broadcast_to(rows, (len(viewers), *rows.shape))
        out["agent"] = rows[viewers]
    if "fleet" in keys:
        fleet = fleet_features(d.free_at, d.time, d.scale)
        out["fleet"] = np.broadcast_to(fleet, (len(viewers), len(FLEET_FEATURES)))
    return out


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


def fleet_features(free_at: np.ndarray, time: np.ndarray | float, scale: float) -> np.ndarray:
    """The fleet in a fixed size: quantiles (:data:`FLEET_QUANTILES`, the nearest
    robot's value at each) and the mean of the robots' times until free, ``/ L``.

    Args:
        free_at: ``float [..., M]`` free times.
        time: ``float [...]`` current decision time(s).
        scale: ``L``.

    Returns:
        ``float32 [..., 8]`` (:data:`FLEET_FEATURES`), whatever ``M``: an ``O(M)``
        selection, no sort.
    """
    m = free_at.shape[-1]
    remaining = np.maximum(free_at - np.asarray(time, dtype=np.float64)[..., None], 0.0)
    kth = sorted({round(q * (m - 1)) for q in FLEET_QUANTILES})
    picked = np.partition(remaining, kth, axis=-1)
    out = np.empty((*free_at.shape[:-1], len(FLEET_FEATURES)), dtype=np.float32)
    out[..., :-1] = picked[..., [round(q * (m - 1)) for q in FLEET_QUANTILES]] / scale
    out[..., -1] = remaining.mean(axis=-1) / scale
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
        distance: ``float [..., N]`` distance from the observing robot to each origin
            (``[V, ..., N]`` for several observers of one queue).
        mask: ``bool [..., N]`` which slots hold a task.
        scale: ``L``.

    Returns:
        ``float32 [..., N, 6]`` (the shape of ``distance`` plus the columns).
    """
    out = np.empty((*distance.shape, 6), dtype=np.float32)
    out[..., :4] = queue_rows / scale
    out[..., 4] = np.where(mask, distance, 0.0) / scale
    out[..., 5] = queue_length / scale
    return out


def nearest_other(chain: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """``float64 [..., N]``: from each destination to the nearest *other* queued origin
    (``chain [..., N, N]`` destinations x origins), ``inf`` for none or an empty slot."""
    n = mask.shape[-1]
    other = mask[..., None, :] & ~np.eye(n, dtype=bool)
    d = np.where(other, chain, np.inf).min(axis=-1, initial=np.inf)
    return np.where(mask, d, np.inf)


def candidate_slots(own_distances: np.ndarray, mask: np.ndarray, k: int) -> np.ndarray:
    """The ``k`` queued tasks a policy scores when the queue holds more: those whose
    origins are nearest the acting robot (ties: the lowest slot), in slot order.

    Args:
        own_distances: ``float [N]`` the acting robot's distance to each origin, as its
            observation holds it (any scale: only the order matters).
        mask: ``bool [N]`` which slots hold a task.
        k: Candidates kept (``>= 1``).

    Returns:
        ``int64 [min(k, N)]`` slot ids, ascending; every one holds a task when at least
        ``k`` do (else the empty slots fill the rest and stay masked).
    """
    n = mask.shape[-1]
    if k >= n:
        return np.arange(n)
    key = np.where(mask, own_distances, np.inf)
    # Stable on (distance, slot): a partition then a sort of the k kept.
    part = np.argpartition(key, k - 1)[:k]
    cut = key[part].max()
    below = np.flatnonzero(key < cut)
    tied = np.flatnonzero(key == cut)[: k - len(below)]
    return np.sort(np.concatenate([below, tied]))


def sim_relations(sim: WarehouseSim) -> tuple[np.ndarray, np.ndarray]:
    """``relations [N, 8]`` and ``rivals [N, K, 4]`` of a simulator's acting robot."""
    obs = decision_features(Decision.of_sim(sim, RELATIONAL_KEYS), RELATIONAL_KEYS)
    return obs["relations"], obs["rivals"]


def sim_observation(
    sim: WarehouseSim, keys: Iterable[str], slots: np.ndarray | None = None
) -> dict[str, np.ndarray]:
    """The acting robot's observation entries ``keys`` and ``action_mask`` (bool), as
    the envs give them (:func:`decision_features`), computing only what ``keys`` need;
    with ``slots int [K]``, the task entries of these slots only (the rows the full
    observation holds for them, bit for bit)."""
    keys = frozenset(keys)
    if slots is not None:
        return decision_features(Decision.of_sim(sim, keys, slots), keys)
    out = sim_acting_view(sim, keys)  # every env step: the same values, fewer copies
    if "fleet" in keys:
        out["fleet"] = fleet_features(sim.robot_free_at, sim.time, sim.layout.scale)
    return out
