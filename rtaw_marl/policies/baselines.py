"""Classical allocation rules: MPDM, RBTS, LoRR's start-kit greedy and uniform random.

Each rule is a :class:`~rtaw_marl.policies.base.Policy` written once, as
:meth:`BaselinePolicy.decide` on a :class:`~rtaw_marl.decision.rule_input.RuleInput`
(what the free robot's observation holds, plus the distance model). Its two paths only build
that input: :meth:`BaselinePolicy.act_sim` from the simulator (the fast path used by
evaluation) and :meth:`BaselinePolicy.act` from a PettingZoo observation (the
``{"observation": features, "action_mask": mask}`` of ``warehouse_v1``, dict or flat;
RBTS needs ``observation="full"``). So both choose the same task for the same state,
once the rule knows the env's distance model, scale and completion noise's mean
(``make_baseline(name, env=env)``, or :meth:`BaselinePolicy.bind`), which ``act``
needs. Ties (within a relative 1e-6) are broken uniformly at random with the policy's
own generator, seeded by :meth:`~BaselinePolicy.reset`: in the paper's two-task setting
MPDM faces two equally close pickups and picks at random.

``mpdm``
    Myopic pickup distance minimisation: the task whose origin is closest to the free
    robot.
``rbts``
    Regret-based task selection as the paper states it: for each task, the distance of
    the closest *other* robot to its origin minus the free robot's distance; choose the
    largest regret. Other robots count at the cell where they will next be free. With a
    single robot there is no other robot and RBTS reduces to MPDM.
``lorr_default``
    The League of Robot Runners' start-kit scheduler (``default_planner/scheduler.cpp``):
    the task of least pickup-plus-delivery travel (the free robot's distance to the
    origin plus the task's length), never reassigned. In ``rtaw-lorr`` the same name
    runs the kit's own C++ scheduler; this is its rule for the own simulator.
``random``
    Uniform over the valid (non-empty) slots.
"""

from __future__ import annotations

import warnings
from abc import ABC, abstractmethod
from collections.abc import Mapping
from typing import Any

import numpy as np

# free_times is re-exported: its home is now the rules' input, next to its two builders.
from rtaw_marl.decision.rule_input import RuleInput, free_times
from rtaw_marl.policies.base import simulator_of
from rtaw_marl.sim.core import WarehouseSim
from rtaw_marl.sim.distances import DistanceModel

__all__ = ["MPDM", "RBTS", "BaselinePolicy", "KitGreedy", "RandomPolicy", "free_times"]

_TIE_RTOL = 1e-6


class BaselinePolicy(ABC):
    """A rule that picks a queue slot for the free robot: :meth:`decide` on a
    :class:`~rtaw_marl.decision.rule_input.RuleInput`, built by :meth:`act_sim` or
    :meth:`act`.

    Args:
        distance_model: The env's distance model, for :meth:`act` when a rule measures
            distances beyond the observation (RBTS, lookahead, hungarian); ``None``
            otherwise. :meth:`act_sim` uses the simulator's.
        scale: Length scale of the observation (``Layout.scale``), to turn observed
            coordinates back into cells on :meth:`act`.
        navigator: Deprecated name of ``distance_model`` (a ``DeprecationWarning``).

    Raises:
        TypeError: Both ``distance_model`` and ``navigator`` are given.

    Attributes:
        needs: The input fields :meth:`decide` reads
            (:data:`~rtaw_marl.decision.rule_input.RULE_NEEDS`); the builders compute
            only these.
    """

    name: str = ""
    needs: frozenset[str] = frozenset()

    def __init__(
        self,
        distance_model: DistanceModel | None = None,
        scale: float = 1.0,
        *,
        navigator: DistanceModel | None = None,
    ) -> None:
        if navigator is not None:
            if distance_model is not None:
                raise TypeError(
                    f"{type(self).__name__}() got both distance_model and navigator "
                    "(its deprecated name)"
                )
            warnings.warn(
                f"{type(self).__name__}(navigator=...) is deprecated, use distance_model=...",
                DeprecationWarning,
                stacklevel=2,
            )
            distance_model = navigator
        self.distance_model = distance_model
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
        """Take the distance model, scale and completion noise's mean of ``env`` (a
        ``WarehouseSim`` or a PettingZoo / Gymnasium warehouse env), so that :meth:`act`
        on its observations chooses what :meth:`act_sim` chooses; returns ``self``."""
        sim = simulator_of(env)
        self.distance_model = sim.distance_model
        self.scale = float(sim.layout.scale)
        self.noise_mean = float(sim.config.noise_mean)
        return self

    def act_sim(self, sim: WarehouseSim) -> int:
        """The slot to assign to ``sim``'s selected robot (its distance model, scale and,
        unless this rule has its own, completion noise's mean)."""
        return self.decide(RuleInput.of_sim(sim, self.needs, self.noise_mean))

    def act(self, observation: Mapping[str, Any]) -> int:
        """The slot to assign, from a ``warehouse_v1`` observation of the free robot.

        Raises:
            ConfigError: The rule needs the env's distance model or noise mean and was not
                built with ``make_baseline(name, env=env)``, or the observation lacks a
                feature it reads.
        """
        decision = RuleInput.of_observation(
            observation, self.needs, distance_model=self.distance_model, scale=self.scale,
            noise_mean=self.noise_mean, reader=self.name,
        )  # fmt: skip
        return self.decide(decision)

    @abstractmethod
    def decide(self, decision: RuleInput) -> int:
        """The slot to assign: the rule itself, on either path's input."""

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
    needs = frozenset(("own_distances",))

    def decide(self, decision: RuleInput) -> int:
        assert decision.own_distances is not None
        return self._nearest(decision.own_distances, decision.mask)


class RBTS(BaselinePolicy):
    """Largest regret: closest other robot's distance minus the free robot's distance."""

    name = "rbts"
    # Robots with equal rows have equal distances: excluding any one of them from the
    # "other robots" gives the same regret, so the fast path skips the row search.
    needs = frozenset(("own_row", "distances"))

    def decide(self, decision: RuleInput) -> int:
        dist, me = decision.distances, decision.robot
        assert dist is not None
        assert me is not None
        if len(dist) == 1:
            return self._pick(-dist[0], decision.mask)
        # The closest other robot: the acting row out of the minimum (on a copy: the
        # input is read-only; one M x N copy is cheaper than two partial minima).
        others = dist.copy()
        others[me] = np.inf
        return self._pick(others.min(axis=0) - dist[me], decision.mask)


class KitGreedy(BaselinePolicy):
    """LoRR's start-kit scheduler: least pickup-plus-delivery travel for the free robot."""

    name = "lorr_default"
    needs = frozenset(("own_distances", "queue_length"))

    def decide(self, decision: RuleInput) -> int:
        assert decision.own_distances is not None
        assert decision.queue_length is not None
        return self._nearest(decision.own_distances + decision.queue_length, decision.mask)


class RandomPolicy(BaselinePolicy):
    """Uniform over the valid slots."""

    name = "random"

    def decide(self, decision: RuleInput) -> int:
        return int(self.rng.choice(np.flatnonzero(decision.mask)))
