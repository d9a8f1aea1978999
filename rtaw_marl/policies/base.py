"""The one policy interface: every rule, the hindsight reference and learned networks.

A policy picks a queue slot for the free robot, in either of two ways that choose the
same slot for the same state:

* ``act(observation)``: on a ``warehouse_v1`` observation ``{"observation":
  features, "action_mask": [N]}`` (``observe`` / ``last()``; dict or flat features);
* ``act_sim(sim)``: the fast path on the bare simulator, used by evaluation.

A hand-written rule is written once, as ``decide`` on one
:class:`~rtaw_marl.decision.rule_input.RuleInput`; ``act_sim`` and ``act`` only build
that input, from the simulator or from the observation
(:class:`~rtaw_marl.policies.baselines.BaselinePolicy`). Rules that need more than the
observation (the distance model to measure distances, the scale, the completion noise's
mean) take it from the env when built with ``make_baseline(name, env=env)``; on
``act_sim`` the simulator gives it. The ``batch`` rule and the ``hindsight`` reference
need what no observation holds (the pickups robots are heading to; the episode's
future): they act on the simulator only, and their ``act`` raises
``NotImplementedError``.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, Protocol, runtime_checkable

from rtaw_marl.sim.core import WarehouseSim

__all__ = ["PlansAhead", "Policy", "simulator_of"]


@runtime_checkable
class Policy(Protocol):
    """What every policy has.

    Attributes:
        name: Label in result tables.
    """

    name: str

    def reset(self, seed: int | None = None) -> None:
        """Seed the policy's own randomness (tie-breaking) for an episode."""

    def act_sim(self, sim: WarehouseSim) -> int:
        """The slot for ``sim``'s selected robot (fast path)."""

    def act(self, observation: Mapping[str, Any]) -> int:
        """The slot for the robot whose ``warehouse_v1`` observation this is."""


@runtime_checkable
class PlansAhead(Protocol):
    """A policy that decides several free robots of a timestep at once
    (:class:`~rtaw_marl.policies.matched.MatchedPolicy`): a caller out of time can send
    the decisions already made instead of letting those robots wait."""

    def pending(self, sim: WarehouseSim) -> tuple[Any, Any]:
        """The robots decided this timestep and not yet served (``int64 [P]``) and their
        slots (``int64 [P]``), each slot's task still queued."""


def simulator_of(source: Any) -> WarehouseSim:
    """The simulator of a ``WarehouseSim``, a PettingZoo or Gymnasium warehouse env
    (wrapped or not).

    Raises:
        TypeError: ``source`` is none of those.
    """
    if isinstance(source, WarehouseSim):
        return source
    sim = getattr(getattr(source, "unwrapped", source), "sim", None)
    if not isinstance(sim, WarehouseSim):
        raise TypeError(
            f"expected a WarehouseSim or a rtaw_marl warehouse env, got {type(source).__name__}"
        )
    return sim
