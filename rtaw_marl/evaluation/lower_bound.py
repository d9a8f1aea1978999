"""A lower bound on the total travel delay of any allocation policy (``drain`` episodes).

In a ``drain`` episode every task of the episode's pre-drawn list is served exactly
once, and each task's empty travel starts at a distinct *end*: the start cell of a robot
(its first task) or the destination of another task (the task its robot did before).
So any policy's TTD is at least the cost of a minimum-cost assignment of distinct ends
to task origins, with a task never following itself. Noise and collisions cannot break
this: with completion noise a TTD is still a distance, and with collision-aware
execution (``sipp``, ``cbs``) a TTD is a real travel time on the grid, never shorter
than the single-robot distance.

Times and the queue are relaxed away but for one piece that is certain: when every
robot is first free at the same time and no task can finish at that very time, the
first decisions go to robots ``0, 1, 2, ...`` in id order (ties go to the lowest id)
before any robot is free again. Robot ``i`` then serves a first task, taken at decision
``i`` from the first ``queue_len + i`` tasks of the list (the only ones queued by then).
Forcing those robots' starts into the assignment, each within its window, lifts the
bound a lot when robots are many (about 2.5x with 100 robots on the 60x60 Table I
settings) and keeps it valid; where the premise cannot be checked (unequal first free
times, a noise draw or zero-length task that could end a task at once) fewer robots or
none are forced.

Solved with ``scipy.optimize.linear_sum_assignment`` on the ``[M + T, T]`` matrix of
distances from ends to origins (about 3.5 s for 1,000 robots and 5,000 tasks on layout
C 256x256 with A*: 2 s of distance fields, 1 s of assignment); forced robots get a
large discount so that every optimum uses them.

Not defined for streams that refill a slot with the task it just lost (``two_task``):
there the tasks served depend on the policy, not on the pre-drawn list.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import linear_sum_assignment

from rtaw_marl.errors import ConfigError
from rtaw_marl.sim.core import WarehouseSim

__all__ = ["ttd_lower_bound"]


def ttd_lower_bound(sim: WarehouseSim, seed: int) -> float:
    """The assignment lower bound on the TTD of episode ``seed`` of ``sim``.

    Args:
        sim: A simulator in ``drain`` mode (it is reset with ``seed``).
        seed: The episode seed; the bound is for that episode's tasks and robot starts.

    Returns:
        A value no policy's episode TTD can go below, for this seed.

    Raises:
        ConfigError: ``sim`` is in ``paper`` mode, where not every task is served, or its
            task stream refills a slot with the task it just lost, where which tasks are
            served depends on the policy.
    """
    if sim.config.episode_mode != "drain":
        raise ConfigError("the TTD lower bound is defined for episode_mode=drain only")
    if sim.stream.refill_same_slot:
        label = getattr(sim.stream, "name", type(sim.stream).__name__)
        raise ConfigError(
            "the TTD lower bound is not defined for task streams that refill the same slot "
            f"({label}): which tasks are served depends on the policy"
        )
    sim.reset(seed)
    tasks = sim.tasks[: sim.config.num_tasks]
    starts = sim.robot_start_xy
    m, t, n = len(starts), len(tasks), sim.queue_len

    # One call: A* computes each origin's distance field once for all ends.
    ends = np.concatenate([starts, tasks[:, 2:]])
    cost = sim.distance_model.distance_matrix(ends, tasks[:, :2])
    # Both distance models are symmetric (Euclidean; shortest paths on an undirected
    # grid), so the diagonal holds each task's length, computed as the simulator does.
    lengths = np.diagonal(cost[m:]).copy()
    forced = _robots_in_id_order(sim, lengths)

    diag = np.arange(t)
    cost[m + diag, diag] = np.inf  # a task never follows itself
    # Robot i (i < forced) takes its first task at decision i: one of the first n + i.
    cost[:forced][diag[None, :] >= n + np.arange(forced)[:, None]] = np.inf
    exact = cost[:forced].copy()
    # Forced robots must start a task: a discount larger than any rearrangement of the
    # other ends can save (t distances) makes every optimum use all of them. A square
    # problem with zero-cost columns for unused ends says the same exactly but solves
    # 10x slower (12 s against 1 s at 1,000 robots x 5,000 tasks).
    longest = float(np.max(cost, where=np.isfinite(cost), initial=0.0))
    discount = float(np.ceil((t + 1) * longest + 1.0))
    cost[:forced] -= discount
    rows, cols = linear_sum_assignment(cost)
    own = rows < forced
    total = float(exact[rows[own], cols[own]].sum()) + float(cost[rows[~own], cols[~own]].sum())
    finite = exact[np.isfinite(exact)]
    if np.array_equal(finite, np.round(finite)):
        return total  # integer distances (A*): the discount was subtracted exactly
    # Otherwise subtracting it rounds each forced entry by up to half an ulp, so the
    # assignment found may cost more than the true optimum by that much per robot.
    return total - forced * float(np.spacing(discount))


def _robots_in_id_order(sim: WarehouseSim, lengths: np.ndarray) -> int:
    """How many robots provably take decisions ``0, 1, ...`` in id order (just reset).

    All robots are first free at the same time ``t0``; decision ``d`` goes to robot ``d``
    as long as every earlier decision's task finishes strictly after ``t0`` (a robot
    free again at ``t0`` would win the tie against every higher id).

    Args:
        sim: The simulator, reset to the episode.
        lengths: ``float64 [T]`` origin -> destination distance of each task.

    Returns:
        ``f`` such that robots ``0 .. f-1`` take decisions ``0 .. f-1``; 0 when the
        robots are first free at different times.
    """
    free = sim.config.robot_free_times
    if free is not None and len({float(x) for x in free}) > 1:
        return 0
    t0 = float(free[0]) if free else 0.0
    k = min(sim.num_robots, len(lengths))
    # Decisions before k take tasks queued by then: the first queue_len + k - 1.
    shortest = float(lengths[: sim.queue_len + k - 1].min())
    # One ulp lower: the finish-time test below must never overestimate a finish.
    shortest = max(0.0, float(np.nextafter(shortest, -np.inf)))
    noise = sim.executor.travel_noise()
    # Collision-aware executors have no noise: a robot free again needs a whole path.
    noise = np.zeros(k) if noise is None else noise[:k]
    # The simulator finishes a task at ((now + ttd) + length) + noise, rounding each sum;
    # rounding is monotone, so with ttd >= 0 this is a lower bound on every finish.
    earliest = (t0 + shortest) + noise
    late = earliest > t0
    first_doubt = np.flatnonzero(~late[: k - 1])
    # Decision d itself still goes to robot d when all decisions before it finish late.
    return k if not first_doubt.size else int(first_doubt[0]) + 1
