"""Two online rules an engineer could write in an afternoon, stronger than MPDM.

``lookahead`` (horizon ``H``)
    For each queued task: give it to the free robot, then play MPDM for ``H`` more
    decisions on the *current queue only* (no future tasks, no refills), with the
    completion noise replaced by its mean and the next decision going to the robot freed
    first. Choose the task with the least total pickup distance over those ``H + 1``
    decisions. All candidates are rolled out at once (vectorised over candidates), so a
    decision costs ``O(H * N * (M + N))``. ``H = 0`` is MPDM, tie-breaking included.
    With ``baselines.lookahead_candidates=K`` and more than ``K`` queued tasks, the
    rollouts play on the ``K`` tasks nearest the free robot only (LoRR's pools).
``hungarian``
    A minimum-cost assignment (``scipy.optimize.linear_sum_assignment``) of the queued
    tasks to all robots, where a robot's cost for a task is its time until free plus the
    distance from the cell where it will be free to the task's origin. The free robot
    takes the task it is matched to, or its nearest task when it is left unmatched.

Both use only what the RTAW observation holds (robot cells and free times, queued tasks)
plus the distance model's distances. With a collision-aware navigator they reason with A*
distances and the planned free times: waiting for other robots is not modelled.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import linear_sum_assignment

from rtaw_marl.decision.features import candidate_slots
from rtaw_marl.decision.rule_input import RuleInput
from rtaw_marl.errors import ConfigError
from rtaw_marl.policies.baselines import BaselinePolicy
from rtaw_marl.policies.search import rollout_start, rollout_take
from rtaw_marl.sim.distances import DistanceModel

__all__ = ["Hungarian", "Lookahead", "lookahead_costs", "rollout_distances"]


def lookahead_costs(
    first: np.ndarray,
    ends: np.ndarray,
    robot: int,
    free_at: np.ndarray,
    now: float,
    lengths: np.ndarray,
    mask: np.ndarray,
    horizon: int,
    noise_mean: float,
) -> np.ndarray:
    """Total pickup distance of each candidate over its ``horizon``-step MPDM rollout.

    Args:
        first: ``float64 [N]`` distances from the free robot to each queued origin.
        ends: ``float64 [M + N, N]`` distances from every robot's cell (rows ``0..M-1``)
            and every queued task's destination (rows ``M..M+N-1``) to each queued origin.
        robot: The free robot.
        free_at: ``float64 [M]`` time each robot becomes free.
        now: The decision time.
        lengths: ``float64 [N]`` origin -> destination length of each queued task.
        mask: ``bool [N]`` which slots hold a task.
        horizon: MPDM decisions simulated after the candidate's own.
        noise_mean: The completion noise's mean, used in place of the noise.

    Returns:
        ``float64 [N]`` cost per slot, ``inf`` for empty slots.
    """
    m, n = len(free_at), len(mask)
    slots = np.flatnonzero(mask)
    k = np.arange(len(slots))
    cost = first[slots].astype(np.float64)
    free, where, left = rollout_start(robot, now, free_at, mask, lengths, noise_mean, slots, cost)
    for _ in range(horizon):
        if not left.any():
            break
        nxt = free.argmin(axis=1)  # ties: the lowest robot id, as the simulator
        d = np.where(left, ends[where[k, nxt]], np.inf)
        j = d.argmin(axis=1)
        dj = d[k, j]
        live = np.isfinite(dj)  # candidates whose rollout still has a task to take
        dj = np.where(live, dj, 0.0)
        cost += dj
        rollout_take(free, where, left, nxt, j, dj, live, lengths, noise_mean, m)
    out = np.full(n, np.inf)
    out[slots] = cost
    return out


class Lookahead(BaselinePolicy):
    """MPDM rollouts of ``horizon`` decisions on the current queue (module docstring).

    Args:
        distance_model: The env's distance model, for :meth:`act` (:meth:`act_sim` uses the
            simulator's).
        scale: Observation length scale (``Layout.scale``).
        horizon: ``H``, MPDM decisions after the candidate's own (``0``: MPDM).
        noise_mean: Mean completion noise of the rollouts; ``None`` (default): the
            simulator's on :meth:`act_sim`, and the env's once bound (:meth:`bind`,
            ``make_baseline("lookahead", env=env)``), which :meth:`act` needs.
        candidates: ``K``: with more queued tasks, roll out on the ``K`` nearest the free
            robot only; ``None``: every queued task.
    """

    name = "lookahead"

    def __init__(
        self,
        distance_model: DistanceModel | None = None,
        scale: float = 1.0,
        *,
        horizon: int,
        noise_mean: float | None = None,
        candidates: int | None = None,
    ) -> None:
        super().__init__(distance_model, scale)
        if isinstance(horizon, bool) or not isinstance(horizon, int) or horizon < 0:
            raise ConfigError(f"lookahead horizon must be an integer >= 0, got {horizon!r}")
        if candidates is not None and (
            isinstance(candidates, bool) or not isinstance(candidates, int) or candidates < 1
        ):
            raise ConfigError(f"lookahead candidates must be an integer >= 1, got {candidates!r}")
        self.horizon = horizon
        self.noise_mean = None if noise_mean is None else float(noise_mean)
        self.candidates = candidates
        # H = 0 is MPDM on the observed distances; rollouts need the robot table, the
        # queue's cells, the distance model and the noise, and K the own distances to rank.
        rollout = ("robot", "robot_xy", "free_in", "queue_rows", "distance_model", "noise_mean")
        ranked = ("own_distances",) if candidates is not None else ()
        self.needs = frozenset(("own_distances",) if horizon == 0 else (*rollout, *ranked))

    def decide(self, decision: RuleInput) -> int:
        mask = decision.mask
        if self.horizon == 0:
            assert decision.own_distances is not None
            return self._nearest(decision.own_distances, mask)
        rows = decision.queue_rows
        assert rows is not None
        if self.candidates is not None and int(mask.sum()) > self.candidates:
            # Large pools: roll out on the K tasks nearest the free robot only (a
            # sub-queue), so a decision costs O(H K (M + K)), not O(H N (M + N)).
            assert decision.own_distances is not None
            sub = candidate_slots(decision.own_distances, mask, self.candidates)
            return int(sub[self._rollout_pick(decision, rows[sub], mask[sub])])
        return self._rollout_pick(decision, rows, mask)

    def _rollout_pick(self, decision: RuleInput, rows: np.ndarray, mask: np.ndarray) -> int:
        """The slot of ``rows int [K, 4]`` (``mask bool [K]``) whose rollout costs least."""
        nav, me, free = decision.distance_model, decision.robot, decision.free_in
        cells, noise = decision.robot_xy, decision.noise_mean
        assert nav is not None
        assert me is not None
        assert free is not None
        assert cells is not None
        assert noise is not None
        ends = rollout_distances(nav, cells, rows, mask)
        lengths = np.zeros(len(mask))
        lengths[mask] = nav.distance(rows[mask, :2], rows[mask, 2:])
        costs = lookahead_costs(  # "now" is 0: free_in counts from the decision
            ends[me], ends, me, free, 0.0, lengths, mask, self.horizon, noise
        )
        return self._nearest(costs, mask)


class Hungarian(BaselinePolicy):
    """The free robot's task in a min-cost assignment of queued tasks to all robots."""

    name = "hungarian"
    needs = frozenset(("robot", "free_in", "distances"))

    def decide(self, decision: RuleInput) -> int:
        dist, wait, robot = decision.distances, decision.free_in, decision.robot
        assert dist is not None
        assert wait is not None
        assert robot is not None
        slots = np.flatnonzero(decision.mask)
        cost = wait[:, None] + dist[:, slots]
        rows, cols = linear_sum_assignment(cost)
        matched = cols[rows == robot]
        if matched.size:
            return int(slots[matched[0]])
        return self._nearest(dist[robot], decision.mask)


def rollout_distances(
    distance_model: DistanceModel, robot_xy: np.ndarray, rows: np.ndarray, mask: np.ndarray
) -> np.ndarray:
    """``float64 [M + N, N]``: distances from each robot's cell, then from each queued
    destination, to each queued origin; ``inf`` for empty slots (rows and columns)."""
    m, n = len(robot_xy), len(mask)
    sources = np.concatenate([robot_xy, rows[mask, 2:]])
    out = np.full((m + n, n), np.inf)
    d = distance_model.distance_matrix(sources, rows[mask, :2])
    live = np.concatenate([np.arange(m), m + np.flatnonzero(mask)])
    out[np.ix_(live, np.flatnonzero(mask))] = d
    return out
