"""The acting robot's view of a decision, compiled: every env step builds one.

In NumPy the acting view is some thirty small array operations whose overhead, not
their arithmetic, was most of an AEC step at ``M = 100`` (34 us of 110).
:func:`acting_view` hands the decision's arrays to two compiled kernels
(:mod:`rtaw_marl.decision._acting`) that compute the same float operations, so the
values equal the NumPy functions' of :mod:`rtaw_marl.decision.features` bit for bit
(tested on batches of decisions).
"""

from __future__ import annotations

from collections.abc import Set
from math import prod
from typing import TYPE_CHECKING

import numpy as np

from rtaw_marl.decision._acting import acting_features
from rtaw_marl.decision._rivals import actor_relations
from rtaw_marl.decision.schema import (
    MISSING,
    NUM_RIVALS,
    RELATION_FEATURES,
    RIVAL_FEATURES,
    SOFTMIN_TEMPERATURE,
    Decision,
)

if TYPE_CHECKING:
    from rtaw_marl.sim.core import WarehouseSim

__all__ = ["acting_view", "sim_acting_view"]


def acting_view(d: Decision, keys: Set[str]) -> dict[str, np.ndarray]:
    """The entries ``keys`` (``fleet`` aside) and ``action_mask`` of the acting robots'
    views (:func:`~rtaw_marl.decision.features.decision_features`): compiled
    (:func:`~rtaw_marl.decision._acting.acting_features`,
    :func:`~rtaw_marl.decision._rivals.actor_relations`), the same values as the NumPy
    functions of :mod:`~rtaw_marl.decision.features` compute for them (tested bit for
    bit)."""
    lead, m, n = d.free_at.shape[:-1], d.free_at.shape[-1], d.queue_mask.shape[-1]
    p = prod(lead)
    coords = not keys.isdisjoint(("robots", "agent", "tasks"))
    relational = not keys.isdisjoint(("relations", "rivals"))
    return _view(
        keys, lead, d.scale, _flat(d.time, _F64, p), _flat(d.robot, _I64, p),
        _flat(d.free_at, _F64, p, m), _flat(d.queue_mask, _BOOL, p, n),
        _flat(d.queue_length, _F64, p, n),
        _flat(d.robot_xy, _I64, p, m, 2) if coords else None,
        _flat(d.queue_rows, _I64, p, n, 4) if coords else None,
        _flat(d.own_distances, _F64, p, n) if "tasks" in keys else None,
        _flat(d.distances, _F64, p, m, n) if relational else None,
        _flat(d.waits, _F64, p, n) if relational else None,
        _flat(d.nearest, _F64, p, n) if relational else None,
    )  # fmt: skip


def sim_acting_view(sim: WarehouseSim, keys: Set[str]) -> dict[str, np.ndarray]:
    """:func:`acting_view` of ``sim``'s current decision, read straight from the
    simulator (no :class:`Decision`, no copies of its kept distances): every AEC env
    step and greedy decision comes here. The same kernels on the same arrays."""
    m, n = sim.num_robots, sim.queue_len
    coords = not keys.isdisjoint(("robots", "agent", "tasks"))
    relational = not keys.isdisjoint(("relations", "rivals"))
    return _view(
        keys, (), sim.layout.scale, np.array((sim.time,)), np.array((sim.robot,), np.int64),
        sim.robot_free_at.reshape(1, m), sim.queue_mask.reshape(1, n),
        sim.queue_length.reshape(1, n),
        sim.robot_xy.reshape(1, m, 2) if coords else None,
        sim.queue_rows.reshape(1, n, 4) if coords else None,
        sim.robot_distances().reshape(1, n) if "tasks" in keys else None,
        sim.distance_matrix(copy=False).reshape(1, m, n) if relational else None,
        sim.queue_waits().reshape(1, n) if relational else None,
        sim.chain_nearest(copy=False).reshape(1, n) if relational else None,
    )  # fmt: skip


def _view(
    keys: Set[str],
    lead: tuple[int, ...],
    scale: float,
    time: np.ndarray,
    robot: np.ndarray,
    free_at: np.ndarray,
    mask: np.ndarray,
    lengths: np.ndarray,
    robot_xy: np.ndarray | None,
    rows: np.ndarray | None,
    own: np.ndarray | None,
    distances: np.ndarray | None,
    waits: np.ndarray | None,
    nearest: np.ndarray | None,
) -> dict[str, np.ndarray]:
    """The kernels on ``P`` decisions' arrays (``[P, ...]``; ``None``: not needed by
    ``keys``); entries shaped ``[*lead, ...]``."""
    (p, m), n = free_at.shape, mask.shape[1]
    out = {"action_mask": np.array(mask.reshape(*lead, n), dtype=bool)}
    if robot_xy is not None and rows is not None:
        robots = np.empty((p, m if "robots" in keys else 0, 3), dtype=np.float32)
        agent = np.empty((p if "agent" in keys else 0, 3), dtype=np.float32)
        tasks = np.empty((p if "tasks" in keys else 0, n, 6), dtype=np.float32)
        acting_features(
            robot_xy, free_at, time, robot, rows, lengths, mask, float(scale),
            lengths if own is None else own, robots, agent, tasks,
        )  # fmt: skip
        if "robots" in keys:
            out["robots"] = robots.reshape(*lead, m, 3)
        if "agent" in keys:
            out["agent"] = agent.reshape(*lead, 3)
        if "tasks" in keys:
            out["tasks"] = tasks.reshape(*lead, n, 6)
    if distances is not None:
        rel = np.empty((p, n, len(RELATION_FEATURES)), dtype=np.float32)
        rivals = np.empty((p, n, NUM_RIVALS, len(RIVAL_FEATURES)), dtype=np.float32)
        actor_relations(
            distances, free_at, time, robot, lengths, waits, nearest, mask, float(scale),
            min(NUM_RIVALS, m - 1), MISSING * scale, SOFTMIN_TEMPERATURE * scale, rel, rivals,
        )  # fmt: skip
        out["relations"] = rel.reshape(*lead, n, len(RELATION_FEATURES))
        out["rivals"] = rivals.reshape(*lead, n, NUM_RIVALS, len(RIVAL_FEATURES))
    return out


def _flat(array: np.ndarray | float | int | None, dtype: np.dtype, *shape: int) -> np.ndarray:
    """``array`` as a ``dtype`` array of ``shape`` (a view when it is one already; a
    scalar or a shared value is repeated). The kernels take any memory layout."""
    # Every env step comes here about ten times: the common cases first, cheaply.
    if type(array) is np.ndarray and array.dtype is dtype and array.size == prod(shape):
        return array.reshape(shape)
    if shape == (1,) and isinstance(array, (int, float, np.integer, np.floating)):
        return np.array((array,), dtype=dtype)
    out = np.asarray(array, dtype=dtype)
    if out.size != prod(shape):
        out = np.broadcast_to(out, shape)
    return np.ascontiguousarray(out.reshape(shape))


_F64, _I64, _BOOL = np.dtype(np.float64), np.dtype(np.int64), np.dtype(np.bool_)
