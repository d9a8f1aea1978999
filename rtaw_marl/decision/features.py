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
from dataclasses import dataclass
from math import prod
from typing import TYPE_CHECKING

import numpy as np

from rtaw_marl.decision._rivals import actor_relations, first_rivals

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

#: Every feature key, in the order of the flat vector (``observation="full"``).
FEATURES = ("robots", "tasks", "agent", "relations", "rivals")
#: Observation keys of the free robot's decision, in the paper network's argument order.
OBSERVATION_KEYS = ("robots", "tasks", "agent", "action_mask")
#: Keys of the relational features (``model=rtaw_plus``).
RELATIONAL_KEYS = ("relations", "rivals")
#: Every key :func:`decision_features` computes: :data:`FEATURES` and ``fleet``, the
#: fixed-size fleet summary that RTAW+'s critic can read (``model.fleet_summary``).
ALL_KEYS = (*FEATURES, "fleet")
#: Quantiles of the fleet's times until free in ``fleet`` (then their mean).
FLEET_QUANTILES = (0.0, 0.1, 0.25, 0.5, 0.75, 0.9, 1.0)
#: Columns of ``fleet``: the quantiles, then the mean, of the robots' times until free.
FLEET_FEATURES = (*(f"free_q{round(100 * q):02d}" for q in FLEET_QUANTILES), "free_mean")
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


def feature_shapes(num_robots: int, queue_len: int) -> dict[str, tuple[int, ...]]:
    """Shape of each entry of one robot's view (``action_mask`` last): ``M``, ``N`` given."""
    m, n = num_robots, queue_len
    return {
        "robots": (m, len(ROBOT_FEATURES)),
        "tasks": (n, len(TASK_FEATURES)),
        "agent": (len(ROBOT_FEATURES),),
        "relations": (n, len(RELATION_FEATURES)),
        "rivals": (n, NUM_RIVALS, len(RIVAL_FEATURES)),
        "fleet": (len(FLEET_FEATURES),),
        "action_mask": (n,),
    }


@dataclass(frozen=True)
class Decision:
    """The arrays a decision's observation is computed from.

    Leading dimensions ``...`` are none for one simulator and ``[B]`` for a batch. The
    arrays are read, never written. The optional ones are needed by some keys only:
    ``own_distances`` by ``tasks``; ``distances``, ``waits`` and ``chain`` by the
    relational keys and by views of other robots (:func:`decision_features`).

    A decision may hold a subset of the queue (:func:`candidate_slots`, the ``K``
    candidates a policy scores): the slot arrays then have ``K`` entries, and
    ``nearest`` still looks over the whole queue.

    Attributes:
        robot_xy: ``int [..., M, 2]`` the cell where each robot will next be free.
        free_at: ``float64 [..., M]`` when each robot is free.
        time: ``float64 [...]`` the decision time.
        robot: ``int [...]`` the acting robot.
        queue_rows: ``int [..., N, 4]`` task cells per slot (zeros when empty).
        queue_length: ``float64 [..., N]`` task lengths (0 when empty).
        queue_mask: ``bool [..., N]`` which slots hold a task.
        scale: ``L``.
        own_distances: ``float64 [..., N]`` the acting robot's distance to each origin.
        distances: ``float64 [..., M, N]`` every robot's distance to each origin.
        waits: ``float64 [..., N]`` time each task has waited in the queue.
        nearest: ``float64 [..., N]`` from each queued destination to the nearest
            origin of another queued task (``inf``: none).
    """

    robot_xy: np.ndarray
    free_at: np.ndarray
    time: np.ndarray | float
    robot: np.ndarray | int
    queue_rows: np.ndarray
    queue_length: np.ndarray
    queue_mask: np.ndarray
    scale: float
    own_distances: np.ndarray | None = None
    distances: np.ndarray | None = None
    waits: np.ndarray | None = None
    nearest: np.ndarray | None = None

    @classmethod
    def of_sim(
        cls, sim: WarehouseSim, keys: Iterable[str] = FEATURES, slots: np.ndarray | None = None
    ) -> Decision:
        """``sim``'s current decision, with only the arrays that ``keys`` need; with
        ``slots int [K]``, of these queue slots only (in their order)."""
        keys = set(keys)
        relational = bool(keys & set(RELATIONAL_KEYS))
        pick = slice(None) if slots is None else np.asarray(slots)
        return cls(
            sim.robot_xy, sim.robot_free_at, sim.time, sim.robot, sim.queue_rows[pick],
            sim.queue_length[pick], sim.queue_mask[pick], sim.layout.scale,
            own_distances=sim.robot_distances()[pick] if "tasks" in keys else None,
            distances=sim.distance_matrix(slots) if relational else None,
            waits=sim.queue_waits()[pick] if relational else None,
            nearest=sim.chain_nearest(slots) if relational else None,
        )  # fmt: skip


def decision_features(
    decision: Decision, keys: Iterable[str], viewers: np.ndarray | None = None
) -> dict[str, np.ndarray]:
    """The observation entries ``keys`` of a decision, computing only what they need.

    Args:
        decision: The decision's arrays.
        keys: Feature keys (:data:`ALL_KEYS`); ``action_mask`` is always included.
        viewers: ``None``: the acting robot's view. ``int [V]`` (one simulator): the
            views of these robots, as each would see the decision if it were acting.

    Returns:
        ``{key: array}``: float32 ``[..., *feature_shapes()[key]]`` (``[V, ...]`` with
        ``viewers``; ``robots`` is then a read-only broadcast of the one table) and
        ``action_mask`` ``bool [..., N]`` (a copy; with ``viewers``, the acting robot's).
    """
    keys, d = set(keys), decision
    out = {"action_mask": np.array(d.queue_mask, dtype=bool)}
    if {"robots", "agent"} & keys:
        rows = robot_features(d.robot_xy, d.free_at, d.time, d.scale)
        if viewers is not None:
            out["robots"] = np.broadcast_to(rows, (len(viewers), *rows.shape))
            out["agent"] = rows[viewers]
        else:
            out["robots"] = rows
            actor = np.asarray(d.robot)[..., None, None]
            out["agent"] = np.take_along_axis(rows, actor, -2)[..., 0, :]
    if "fleet" in keys:
        fleet = fleet_features(d.free_at, d.time, d.scale)
        out["fleet"] = fleet if viewers is None else np.broadcast_to(fleet, (len(viewers), 8))
    if "tasks" in keys:
        own = d.own_distances if viewers is None else d.distances[viewers]
        out["tasks"] = task_features(d.queue_rows, d.queue_length, own, d.queue_mask, d.scale)
    if set(RELATIONAL_KEYS) & keys:
        who = np.asarray(d.robot)[..., None] if viewers is None else np.asarray(viewers)
        remaining = d.free_at - np.asarray(d.time, dtype=np.float64)[..., None]
        rel, rivals = relational_features(
            d.distances, remaining, who, d.queue_length, d.waits, d.nearest, d.queue_mask,
            d.scale,
        )  # fmt: skip
        # One view per leading index: drop the viewer axis.
        out["relations"], out["rivals"] = (rel, rivals) if viewers is not None else (
            rel[..., 0, :, :], rivals[..., 0, :, :, :]
        )  # fmt: skip
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
            np.ascontiguousarray(dist, dtype=np.float64), np.ascontiguousarray(rem),
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
    keys = tuple(keys)
    return decision_features(Decision.of_sim(sim, keys, slots), keys)
