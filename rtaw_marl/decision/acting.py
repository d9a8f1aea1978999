"""The acting robot's view of a decision, compiled: every env step builds one.

In NumPy the acting view is some thirty small array operations whose overhead, not
their arithmetic, was most of an AEC step at ``M = 100`` (34 us of 110).
:func:`acting_view` hands the decision's arrays to two compiled kernels
(:mod:`rtaw_marl.decision._acting`) that compute the same float operations, so the
values equal the NumPy functions' of :mod:`rtaw_marl.decision.features` bit for bit
(tested on batches of decisions).
"""

from __future__ import annotations

from math import prod

import numpy as np

from rtaw_marl.decision._acting import acting_features, acting_relations
from rtaw_marl.decision.schema import (
    MISSING,
    NUM_RIVALS,
    RELATION_FEATURES,
    RIVAL_FEATURES,
    SOFTMIN_TEMPERATURE,
    Decision,
)

__all__ = ["acting_view"]


def acting_view(d: Decision, keys: set[str]) -> dict[str, np.ndarray]:
    """The entries ``keys`` (``fleet`` aside) and ``action_mask`` of the acting robots'
    views (:func:`~rtaw_marl.decision.features.decision_features`): compiled
    (:func:`~rtaw_marl.decision._acting.acting_features`,
    :func:`~rtaw_marl.decision._acting.acting_relations`), the same values as this
    module's NumPy functions compute for them (tested bit for bit). Every env step
    comes here, so it makes no array it does not need."""
    lead, m, n = d.free_at.shape[:-1], d.free_at.shape[-1], d.queue_mask.shape[-1]
    p = prod(lead)
    time, robot = _flat(d.time, _F64, p), _flat(d.robot, _I64, p)
    free_at, mask = _flat(d.free_at, _F64, p, m), _flat(d.queue_mask, _BOOL, p, n)
    lengths = _flat(d.queue_length, _F64, p, n)
    out = {"action_mask": np.array(d.queue_mask, dtype=bool)}
    if "robots" in keys or "agent" in keys or "tasks" in keys:
        robots = np.empty((p, m if "robots" in keys else 0, 3), dtype=np.float32)
        agent = np.empty((p if "agent" in keys else 0, 3), dtype=np.float32)
        tasks = np.empty((p if "tasks" in keys else 0, n, 6), dtype=np.float32)
        own = _flat(d.own_distances, _F64, p, n) if "tasks" in keys else lengths
        acting_features(
            _flat(d.robot_xy, _I64, p, m, 2), free_at, time, robot,
            _flat(d.queue_rows, _I64, p, n, 4), lengths, mask, float(d.scale), own,
            robots, agent, tasks,
        )  # fmt: skip
        if "robots" in keys:
            out["robots"] = robots.reshape(*lead, m, 3)
        if "agent" in keys:
            out["agent"] = agent.reshape(*lead, 3)
        if "tasks" in keys:
            out["tasks"] = tasks.reshape(*lead, n, 6)
    if "relations" in keys or "rivals" in keys:
        rel = np.empty((p, n, len(RELATION_FEATURES)), dtype=np.float32)
        rivals = np.empty((p, n, NUM_RIVALS, len(RIVAL_FEATURES)), dtype=np.float32)
        acting_relations(
            _flat(d.distances, _F64, p, m, n), free_at, time, robot, lengths,
            _flat(d.waits, _F64, p, n), _flat(d.nearest, _F64, p, n), mask,
            float(d.scale), min(NUM_RIVALS, m - 1), MISSING * d.scale,
            SOFTMIN_TEMPERATURE * d.scale, rel, rivals,
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
