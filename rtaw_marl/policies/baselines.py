"""Classical allocation rules: MPDM, RBTS and uniform random.

Each rule is a :class:`~rtaw_marl.policies.base.Policy`: it acts either on the simulator
directly (:meth:`BaselinePolicy.act_sim`, the fast path used by evaluation) or on a
PettingZoo observation (:meth:`act`: the ``{"observation": features, "action_mask":
mask}`` of ``warehouse_v1``, dict or flat; RBTS needs ``observation="full"``), and
both paths choose the same task for the same state once the rule is bound to the env
(:meth:`BaselinePolicy.bind`, or ``make_baseline(name, env=env)``), which gives it the
navigator, the scale and the completion noise's mean. Ties (within a relative 1e-6) are broken
uniformly at random with the policy's own generator, seeded by :meth:`reset`: in the
paper's two-task setting MPDM faces two equally close pickups and picks at random.

``mpdm``
    Myopic pickup distance minimisation: the task whose origin is closest to the free
    robot.
``rbts``
    Regret-based task selection as the paper states it: for each task, the distance of
    the closest *other* robot to its origin minus the free robot's distance; choose the
    largest regret. Other robots count at the cell where they will next be free. With a
    single robot there is no other robot and RBTS reduces to MPDM.
``random``
    Uniform over the valid (non-empty) slots.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Mapping
from typing import Any

import numpy as np

from rtaw_marl.decision.observations import read_features
from rtaw_marl.errors import ConfigError
from rtaw_marl.policies.base import simulator_of
from rtaw_marl.sim.core import WarehouseSim
from rtaw_marl.sim.distances import DistanceModel

__all__ = ["MPDM", "RBTS", "BaselinePolicy", "RandomPolicy", "free_times"]

_TIE_RTOL = 1e-6


def free_times(column: np.ndarray, scale: float) -> np.ndarray:
    """``float64 [M]`` times until free from the observed ``time_until_free / L`` column.

    The observation is float32: where a time to the millisecond is what the observation
    holds (it rounds to the same float32), that time is taken, so that robots freed at
    the same second still tie (and the lowest id goes first) as in the simulator; other
    times (with completion noise) keep the observation's own value.
    """
    column = np.asarray(column, dtype=np.float32)
    times = column.astype(np.float64) * scale
    rounded = np.round(times, 3)
    return np.where((rounded / scale).astype(np.float32) == column, rounded, times)


class BaselinePolicy(ABC):
    """A rule that picks a queue slot for the free robot.

    Args:
        navigator: Needed by rules that measure distances beyond the observation
            (RBTS on the observation path); ``None`` otherwise.
        scale: Length scale of the observation (``Layout.scale``), to turn observed
            coordinates back into cells.
    """

    name: str = ""

    def __init__(self, navigator: DistanceModel | None = None, scale: float = 1.0) -> None:
        self.navigator = navigator
        self.scale = float(scale)
        #: Mean completion noise, for rules that model it (``None``: the simulator's).
        self.noise_mean: float | None = None
        # Seeded from the start: a rule used without reset() still breaks ties the same
        # way in every process (an unseeded teacher once made warm starts irreproducible).
        self.reset(0)

    def reset(self, seed: int | None = None) -> None:
        """Seed the tie-breaking generator (an independent stream of the episode seed;
        fresh entropy for ``None``)."""
        self.rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(3,)))

    def bind(self, env: Any) -> BaselinePolicy:
        """Take the navigator, scale and completion noise's mean of ``env`` (a
        ``WarehouseSim`` or a PettingZoo / Gymnasium warehouse env), so that :meth:`act`
        on its observations chooses what :meth:`act_sim` chooses; returns ``self``."""
        sim = simulator_of(env)
        self.navigator = sim.navigator
        self.scale = float(sim.layout.scale)
        self.noise_mean = float(sim.config.noise_mean)
        return self

    @abstractmethod
    def act_sim(self, sim: WarehouseSim) -> int:
        """The slot to assign to ``sim``'s selected robot."""

    @abstractmethod
    def act(self, observation: Mapping[str, np.ndarray]) -> int:
        """The slot to assign, from a ``warehouse_v1`` observation of the free robot."""

    def _nearest(self, d: np.ndarray, mask: np.ndarray) -> int:
        """Index of the smallest ``d`` among ``mask``; ties broken at random."""
        best = d[mask].min()
        candidates = np.flatnonzero(mask & (d <= best + _TIE_RTOL * max(1.0, float(best))))
        if candidates.size == 1:
            return int(candidates[0])
        return int(self.rng.choice(candidates))

    def _pick(self, scores: np.ndarray, mask: np.ndarray) -> int:
        """Index of the largest score among ``mask``; ties broken at random."""
        best = scores[mask].max()
        tol = _TIE_RTOL * max(1.0, abs(float(best)))
        candidates = np.flatnonzero(mask & (scores >= best - tol))
        if candidates.size == 1:
            return int(candidates[0])
        return int(self.rng.choice(candidates))


class MPDM(BaselinePolicy):
    """Nearest pickup for the free robot."""

    name = "mpdm"

    def act_sim(self, sim: WarehouseSim) -> int:
        d = sim.robot_distances()
        return self._nearest(d, sim.queue_mask)

    def act(self, observation: Mapping[str, np.ndarray]) -> int:
        tasks = read_features(observation, ("tasks",), self.name)["tasks"]
        d = np.asarray(tasks[:, 4], dtype=np.float64) * self.scale
        return self._nearest(d, np.asarray(observation["action_mask"], dtype=bool))


class RBTS(BaselinePolicy):
    """Largest regret: closest other robot's distance minus the free robot's distance."""

    name = "rbts"

    def act_sim(self, sim: WarehouseSim) -> int:
        if sim.num_robots == 1:
            return self._pick(-sim.robot_distances(), sim.queue_mask)
        dist = sim.distance_matrix()
        return self._regret_pick(dist, sim.robot, sim.queue_mask)

    def act(self, observation: Mapping[str, np.ndarray]) -> int:
        if self.navigator is None:
            raise ConfigError(
                "RBTS on observations needs the env's navigator: make_baseline('rbts', env=env)"
            )
        mask = np.asarray(observation["action_mask"], dtype=bool)
        features = read_features(observation, ("robots", "tasks", "agent"), self.name)
        robots = features["robots"]
        cells = np.rint(robots[:, :2].astype(np.float64) * self.scale).astype(np.int64)
        origins = np.rint(features["tasks"][:, :2].astype(np.float64) * self.scale)
        origins = origins.astype(np.int64)
        # The free robot is the row equal to the agent's own features; robots sharing
        # a cell and a free time have equal rows, and excluding any one of them is the same.
        me = int(np.all(robots == features["agent"], axis=1).argmax())
        if len(robots) == 1:
            d = self.navigator.distance_matrix(cells, origins[mask])
            scores = np.full(len(mask), -np.inf)
            scores[mask] = -d[0]
            return self._pick(scores, mask)
        dist = np.zeros((len(robots), len(mask)))
        dist[:, mask] = self.navigator.distance_matrix(cells, origins[mask])
        return self._regret_pick(dist, me, mask)

    def _regret_pick(self, dist: np.ndarray, me: int, mask: np.ndarray) -> int:
        mine = dist[me].copy()
        dist[me] = np.inf
        regret = dist.min(axis=0) - mine
        return self._pick(regret, mask)


class RandomPolicy(BaselinePolicy):
    """Uniform over the valid slots."""

    name = "random"

    def act_sim(self, sim: WarehouseSim) -> int:
        return int(self.rng.choice(np.flatnonzero(sim.queue_mask)))

    def act(self, observation: Mapping[str, np.ndarray]) -> int:
        return int(self.rng.choice(np.flatnonzero(observation["action_mask"])))
