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
plus navigator distances. With a collision-aware navigator they reason with A*
distances and the planned free times: waiting for other robots is not modelled.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
from scipy.optimize import linear_sum_assignment

from rtaw_marl.decision.features import candidate_slots, robot_features
from rtaw_marl.decision.observations import read_features
from rtaw_marl.errors import ConfigError
from rtaw_marl.policies.baselines import BaselinePolicy, free_times
from rtaw_marl.sim.core import WarehouseSim
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
    free = np.tile(free_at, (len(slots), 1))
    where = np.tile(np.arange(m), (len(slots), 1))  # row of `ends` each robot stands at
    left = np.tile(mask, (len(slots), 1))
    free[k, robot] = np.maximum(now, now + cost + lengths[slots] + noise_mean)
    where[k, robot] = m + slots
    left[k, slots] = False
    for _ in range(horizon):
        if not left.any():
            break
        nxt = free.argmin(axis=1)  # ties: the lowest robot id, as the simulator
        t = free[k, nxt]
        d = np.where(left, ends[where[k, nxt]], np.inf)
        j = d.argmin(axis=1)
        dj = d[k, j]
        live = np.isfinite(dj)  # candidates whose rollout still has a task to take
        cost += np.where(live, dj, 0.0)
        done_at = np.maximum(t, t + dj + lengths[j] + noise_mean)
        free[k, nxt] = np.where(live, done_at, free[k, nxt])
        where[k, nxt] = np.where(live, m + j, where[k, nxt])
        left[k[live], j[live]] = False
    out = np.full(n, np.inf)
    out[slots] = cost
    return out


class Lookahead(BaselinePolicy):
    """MPDM rollouts of ``horizon`` decisions on the current queue (module docstring).

    Args:
        navigator: Distances (also used on the observation path).
        scale: Observation length scale (``Layout.scale``).
        horizon: ``H``, MPDM decisions after the candidate's own (``0``: MPDM).
        noise_mean: Mean completion noise of the rollouts; ``None`` (default): the
            simulator's on :meth:`act_sim`, and the env's once bound (:meth:`bind`,
            ``make_baseline("lookahead", env=env)``), which :meth:`act` needs.
    """

    name = "lookahead"

    def __init__(
        self,
        navigator: DistanceModel | None = None,
        scale: float = 1.0,
        *,
        horizon: int,
        noise_mean: float | None = None,
        candidates: int | None = None,
    ) -> None:
        super().__init__(navigator, scale)
        if isinstance(horizon, bool) or not isinstance(horizon, int) or horizon < 0:
            raise ConfigError(f"lookahead horizon must be an integer >= 0, got {horizon!r}")
        if candidates is not None and (
            isinstance(candidates, bool) or not isinstance(candidates, int) or candidates < 1
        ):
            raise ConfigError(f"lookahead candidates must be an integer >= 1, got {candidates!r}")
        self.horizon = horizon
        self.noise_mean = None if noise_mean is None else float(noise_mean)
        self.candidates = candidates

    def act_sim(self, sim: WarehouseSim) -> int:
        if self.horizon == 0:
            return self._nearest(sim.robot_distances(), sim.queue_mask)
        noise = sim.config.noise_mean if self.noise_mean is None else self.noise_mean
        robots, me = _observed_robots(sim)
        rows, mask = sim.queue_rows, sim.queue_mask
        if self.candidates is not None and int(mask.sum()) > self.candidates:
            # Large pools: roll out on the K tasks nearest the free robot only (a
            # sub-queue), so a decision costs O(H K (M + K)), not O(H N (M + N)).
            sub = candidate_slots(sim.robot_distances(), mask, self.candidates)
            pick = self._choose(
                sim.navigator, sim.layout.scale, robots, me, rows[sub], mask[sub], noise
            )
            return int(sub[pick])
        return self._choose(sim.navigator, sim.layout.scale, robots, me, rows, mask, noise)

    def act(self, observation: Mapping[str, np.ndarray]) -> int:
        if self.navigator is None or (self.horizon and self.noise_mean is None):
            raise ConfigError(
                "lookahead on observations needs the env's navigator and noise mean: "
                "make_baseline('lookahead', env=env)"
            )
        mask = np.asarray(observation["action_mask"], dtype=bool)
        keys = ("tasks",) if self.horizon == 0 else ("robots", "tasks", "agent")
        features = read_features(observation, keys, self.name)
        tasks = features["tasks"].astype(np.float64) * self.scale
        if self.horizon == 0:
            return self._nearest(tasks[:, 4], mask)
        robots = features["robots"]
        me = _acting_row(robots.astype(np.float64), features["agent"])
        rows = np.rint(tasks[:, :4]).astype(np.int64)
        return self._choose(self.navigator, self.scale, robots, me, rows, mask, self.noise_mean)

    def _choose(
        self,
        navigator: DistanceModel,
        scale: float,
        robots: np.ndarray,
        me: int,
        rows: np.ndarray,
        mask: np.ndarray,
        noise_mean: float,
    ) -> int:
        """The choice from what the observation holds, on both paths: ``float32 [M, 3]``
        robot rows (so near-ties are decided alike), the acting row, the queue's cells."""
        cells = np.rint(robots[:, :2].astype(np.float64) * scale).astype(np.int64)
        ends = rollout_distances(navigator, cells, rows, mask)
        lengths = np.zeros(len(mask))
        lengths[mask] = navigator.distance(rows[mask, :2], rows[mask, 2:])
        free = free_times(robots[:, 2], scale)  # "now" is 0
        costs = lookahead_costs(
            ends[me], ends, me, free, 0.0, lengths, mask, self.horizon, noise_mean
        )
        return self._nearest(costs, mask)


class Hungarian(BaselinePolicy):
    """The free robot's task in a min-cost assignment of queued tasks to all robots."""

    name = "hungarian"

    def act_sim(self, sim: WarehouseSim) -> int:
        robots, me = _observed_robots(sim)
        wait = free_times(robots[:, 2], sim.layout.scale)
        return self._choose(sim.distance_matrix(), wait, me, sim.queue_mask)

    def act(self, observation: Mapping[str, np.ndarray]) -> int:
        if self.navigator is None:
            raise ConfigError(
                "hungarian on observations needs the env's navigator: "
                "make_baseline('hungarian', env=env)"
            )
        mask = np.asarray(observation["action_mask"], dtype=bool)
        features = read_features(observation, ("robots", "tasks", "agent"), self.name)
        robots = features["robots"].astype(np.float64)
        cells = np.rint(robots[:, :2] * self.scale).astype(np.int64)
        origins = np.rint(features["tasks"][:, :2].astype(np.float64) * self.scale)
        dist = np.zeros((len(robots), len(mask)))
        dist[:, mask] = self.navigator.distance_matrix(cells, origins[mask].astype(np.int64))
        me = _acting_row(robots, features["agent"])
        return self._choose(dist, free_times(features["robots"][:, 2], self.scale), me, mask)

    def _choose(self, dist: np.ndarray, wait: np.ndarray, robot: int, mask: np.ndarray) -> int:
        slots = np.flatnonzero(mask)
        cost = wait[:, None] + dist[:, slots]
        rows, cols = linear_sum_assignment(cost)
        matched = cols[rows == robot]
        if matched.size:
            return int(slots[matched[0]])
        return self._nearest(dist[robot], mask)


def rollout_distances(
    navigator: DistanceModel, robot_xy: np.ndarray, rows: np.ndarray, mask: np.ndarray
) -> np.ndarray:
    """``float64 [M + N, N]``: distances from each robot's cell, then from each queued
    destination, to each queued origin; ``inf`` for empty slots (rows and columns)."""
    m, n = len(robot_xy), len(mask)
    sources = np.concatenate([robot_xy, rows[mask, 2:]])
    out = np.full((m + n, n), np.inf)
    d = navigator.distance_matrix(sources, rows[mask, :2])
    live = np.concatenate([np.arange(m), m + np.flatnonzero(mask)])
    out[np.ix_(live, np.flatnonzero(mask))] = d
    return out


def _observed_robots(sim: WarehouseSim) -> tuple[np.ndarray, int]:
    """``float32 [M, 3]`` robot rows as the observation holds them (times until free
    clipped at 0: a robot idle since before now starts now) and the acting robot's row as
    :meth:`act` finds it (of identical robots, the first: they are interchangeable)."""
    robots = robot_features(sim.robot_xy, sim.robot_free_at, sim.time, sim.layout.scale)
    return robots, _acting_row(robots.astype(np.float64), robots[sim.robot])


def _acting_row(robots: np.ndarray, agent: np.ndarray) -> int:
    """The acting robot's row: equal rows are interchangeable for these rules."""
    return int(np.all(robots == np.asarray(agent, dtype=np.float64), axis=1).argmax())
