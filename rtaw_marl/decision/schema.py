"""The observation's schema: its keys, the columns of each entry and their shapes, and
the :class:`Decision` arrays every entry is computed from.

The one place these are written; :mod:`rtaw_marl.decision.features` computes the values
and re-exports every name.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

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
    "feature_shapes",
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
        keys = keys if isinstance(keys, frozenset) else frozenset(keys)
        relational = not keys.isdisjoint(RELATIONAL_KEYS)
        pick = slice(None) if slots is None else np.asarray(slots)
        return cls(
            sim.robot_xy, sim.robot_free_at, sim.time, sim.robot, sim.queue_rows[pick],
            sim.queue_length[pick], sim.queue_mask[pick], sim.layout.scale,
            own_distances=sim.robot_distances()[pick] if "tasks" in keys else None,
            distances=sim.distance_matrix(slots) if relational else None,
            waits=sim.queue_waits()[pick] if relational else None,
            nearest=sim.chain_nearest(slots) if relational else None,
        )  # fmt: skip
