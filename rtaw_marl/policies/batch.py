"""``batch``: the rule LoRR-scale systems use, a min-cost matching of every robot free now
to the queued tasks, with a cap on robots converging on one pickup region.

At a decision at time ``t`` the free robots ``F`` (free at ``t``: in lifelong execution
many finish in one timestep) are matched to the queued tasks by
``scipy.optimize.linear_sum_assignment`` on the cost

    ``distance(robot's cell, task's origin) + penalty x [region load >= cap]``

where a task's *region* is the ``region x region`` block of cells holding its origin,
and its *load* the robots already heading to a pickup in that block (served tasks not
yet picked up by their planned times). The acting robot takes the task it is matched
to; the next free robot of the timestep solves the same problem without it. With one
free robot and no loaded region this is MPDM. The penalty is a soft cap: a robot goes
to a capped region only when every other choice is costlier by ``penalty``.

The matching costs ``O(|F|^2 N)`` and needs the fields of the ``|F|`` robot cells
only (``|F|`` is capped at ``baselines.batch_max`` = 256: a whole fleet freed at
``t = 0`` is matched in chunks of robots in id order), so it runs on LoRR's pools
(``N = 15,000``), unlike ``hungarian``, whose all-robots matrix is ``M x N``.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
from scipy.optimize import linear_sum_assignment

from rtaw_marl.sim.core import WarehouseSim

__all__ = ["BatchAssignment", "capped_costs", "match"]

_SIM_ONLY = (
    "batch acts on the simulator only: the observation does not say which robots "
    "are heading to pickups; evaluate it with rtaw-eval or act_sim"
)


def match(cost: np.ndarray) -> np.ndarray:
    """The column matched to each row of ``cost [R, C]`` (``R <= C``) in a minimum-cost
    assignment, ``int64 [R]``."""
    rows, cols = linear_sum_assignment(cost)
    out = np.empty(cost.shape[0], dtype=np.int64)
    out[rows] = cols
    return out


def capped_costs(
    dist: np.ndarray, origins: np.ndarray, heading: np.ndarray, region: int, cap: int,
    penalty: float,
) -> np.ndarray:  # fmt: skip
    """``dist [R, K]`` plus ``penalty`` on tasks whose pickup region already has ``cap``
    robots heading to it.

    Args:
        dist: Distances from the free robots to the tasks' origins.
        origins: ``int [K, 2]`` the tasks' origins.
        heading: ``int [H, 2]`` origins the busy robots are heading to.
        region: The side of a region, in cells.
        cap: Robots per region before the penalty applies.
        penalty: Added cost (distance units).
    """
    keys = origins[:, 1] // region * 1_000_003 + origins[:, 0] // region
    busy = heading[:, 1] // region * 1_000_003 + heading[:, 0] // region
    regions, load = np.unique(busy, return_counts=True)
    if not len(regions):
        return dist.copy()
    at = np.searchsorted(regions, keys)
    found = (at < len(regions)) & (regions[np.minimum(at, len(regions) - 1)] == keys)
    full = found & (load[np.minimum(at, len(regions) - 1)] >= cap)
    return dist + penalty * full[None, :]


class BatchAssignment:
    """Min-cost matching of the robots free now to the queued tasks, with a soft cap of
    robots per pickup region. It acts on the simulator only (:meth:`act_sim`), like the
    ``hindsight`` reference: the matching needs what no observation holds (the robots
    free in this timestep, the pickups robots are heading to), so it is not a
    :class:`~rtaw_marl.policies.baselines.BaselinePolicy` deciding from a
    :class:`~rtaw_marl.decision.rule_input.RuleInput`. Its choices are deterministic.

    Args:
        region: Side of a pickup region, in cells.
        cap: Robots heading to one region before its tasks cost ``penalty`` more.
        penalty: That extra cost, in cells of travel.
        max_batch: Most robots matched in one problem (the acting robot and the next
            free ones by id).
    """

    name = "batch"

    def __init__(
        self, region: int = 8, cap: int = 4, penalty: float = 20.0, max_batch: int = 256
    ) -> None:
        self.region, self.cap, self.penalty = int(region), int(cap), float(penalty)
        self.max_batch = int(max_batch)
        self.reset()

    def reset(self, seed: int | None = None) -> None:
        """Forget the last timestep's matching (the seed is unused: no random ties)."""
        self._plan: tuple[int, float, dict[int, int]] | None = None

    def act_sim(self, sim: WarehouseSim) -> int:
        # One matching per timestep: the robots freed in it take their matched tasks
        # while those are still queued (a later robot re-solves only if one is gone).
        if self._plan is not None and self._plan[:2] == (id(sim), sim.time):
            task = self._plan[2].get(sim.robot)
            if task is not None:
                slot = np.flatnonzero(sim.queue_ids == task)
                if slot.size:
                    return int(slot[0])
        return self._solve(sim)

    def _solve(self, sim: WarehouseSim) -> int:
        slots = np.flatnonzero(sim.queue_mask)
        free = sim.free_robots()
        # The robots deciding next (in id order, as the simulator asks them), at most
        # max_batch: a fleet freed at once (t = 0) is matched in chunks, not as one
        # M x N problem.
        free = free[free >= sim.robot][: self.max_batch]
        me = 0
        if len(free) > len(slots):
            # More free robots than tasks: those nearest the tasks are served first.
            free = free[:1]
        dist = sim.robot_distances_many(free, slots)
        cost = capped_costs(
            dist, sim.queue_rows[slots, :2], _heading(sim), self.region, self.cap, self.penalty
        )
        cols = match(cost)
        self._plan = (
            id(sim),
            sim.time,
            dict(zip(free.tolist(), sim.queue_ids[slots[cols]].tolist(), strict=True)),
        )
        return int(slots[cols[me]])

    def act(self, observation: Mapping[str, Any]) -> int:
        """Not available: use :meth:`act_sim` (the class docstring says why).

        Raises:
            NotImplementedError: Always; use :meth:`act_sim` on the simulator.
        """
        raise NotImplementedError(_SIM_ONLY)


def _heading(sim: WarehouseSim) -> np.ndarray:
    """Origins ``int64 [H, 2]`` of the served tasks not yet picked up at ``sim.time``
    (by their planned pickup times: assignment + TTD)."""
    served = sim.task_robot >= 0
    pickup = sim.task_assigned + sim.task_ttd
    pending = np.flatnonzero(served & (pickup > sim.time))
    return sim.tasks[pending, :2]
