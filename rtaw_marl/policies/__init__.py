"""Allocation policies: the classical rules, stronger hand-written rules, the hindsight
reference, and trained RTAW networks, all behind one interface (:class:`Policy`:
``name``, ``reset(seed)``, ``act(observation)``, ``act_sim(sim)``).

``load_policy`` and ``NetworkPolicy`` (:mod:`.network`) need torch; they are imported
on first use, so ``import rtaw_marl.policies`` stays light. Without the ``train`` extra,
using either raises one :class:`~rtaw_marl.errors.MissingExtraError` naming it.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from rtaw_marl.errors import missing_extra, unknown_name
from rtaw_marl.policies.base import Policy, simulator_of
from rtaw_marl.policies.baselines import MPDM, RBTS, BaselinePolicy, KitGreedy, RandomPolicy
from rtaw_marl.policies.batch import BatchAssignment
from rtaw_marl.policies.config import BaselinesConfig
from rtaw_marl.policies.hindsight import Hindsight
from rtaw_marl.policies.lookahead import Hungarian, Lookahead
from rtaw_marl.policies.pairs import PairGreedy

if TYPE_CHECKING:
    from rtaw_marl.policies.network import NetworkPolicy, load_policy

__all__ = [
    "BASELINES",
    "MPDM",
    "RBTS",
    "BaselinePolicy",
    "BaselinesConfig",
    "BatchAssignment",
    "Hindsight",
    "Hungarian",
    "KitGreedy",
    "Lookahead",
    "NetworkPolicy",
    "PairGreedy",
    "Policy",
    "RandomPolicy",
    "load_policy",
    "make_baseline",
]

_Factory = Callable[[BaselinesConfig], "BaselinePolicy | BatchAssignment | Hindsight | PairGreedy"]

#: Every rule evaluated by name (``rtaw-eval policy=[...]``): its parameters -> the rule,
#: not yet bound to an env (:func:`make_baseline` binds it).
BASELINES: dict[str, _Factory] = {
    MPDM.name: lambda _: MPDM(),
    RBTS.name: lambda _: RBTS(),
    RandomPolicy.name: lambda _: RandomPolicy(),
    KitGreedy.name: lambda _: KitGreedy(),
    Lookahead.name: lambda p: Lookahead(
        horizon=p.lookahead_horizon, candidates=p.lookahead_candidates
    ),
    Hungarian.name: lambda _: Hungarian(),
    BatchAssignment.name: lambda p: BatchAssignment(
        region=p.batch_region, cap=p.batch_cap, penalty=p.batch_penalty, max_batch=p.batch_max
    ),
    Hindsight.name: lambda p: Hindsight(p.hindsight_horizon),
    PairGreedy.name: lambda _: PairGreedy(),
}

#: Names served lazily from :mod:`.network` (torch).
_NETWORK = ("NetworkPolicy", "load_policy")


def make_baseline(
    name: str, *, env: Any = None, params: BaselinesConfig | None = None
) -> BaselinePolicy | BatchAssignment | Hindsight | PairGreedy:
    """Build the rule registered as ``name``.

    ``make_baseline(name)`` is all evaluation needs: ``act_sim(sim)`` takes the
    distance model, the scale and the completion noise's mean from the simulator it is
    given. ``make_baseline(name, env=env)`` also lets the rule act on ``env``'s
    observations, ``act(obs)``, choosing what ``act_sim`` would.

    Args:
        name: ``mpdm``, ``rbts``, ``lorr_default``, ``random``, ``lookahead``,
            ``hungarian``, ``batch``, ``pair_greedy`` or ``hindsight``.
        env: A PettingZoo or Gymnasium warehouse env (wrapped or not) or its
            ``WarehouseSim``: the rule takes its distance model, scale and completion noise's
            mean (:meth:`BaselinePolicy.bind`); ``None``: a rule for ``act_sim``.
        params: Rule parameters (horizons, candidates, batch sizes); the defaults when
            ``None``.

    Raises:
        ConfigError: Unknown name (the message lists the available ones).
        TypeError: ``env`` is not a warehouse env or simulator.
    """
    try:
        factory = BASELINES[name]
    except KeyError:
        raise unknown_name("policy", name, list(BASELINES)) from None
    sim = None if env is None else simulator_of(env)
    policy = factory(params or BaselinesConfig())
    if sim is not None and isinstance(policy, BaselinePolicy):
        policy.bind(sim)
    return policy


def __getattr__(name: str) -> Any:
    # load_policy and NetworkPolicy need torch: import it on first use only, and name the
    # extra to install rather than the module that was missing.
    if name in _NETWORK:
        try:
            from rtaw_marl.policies import network
        except ModuleNotFoundError as exc:
            raise missing_extra(exc, name, "train") from None
        return getattr(network, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
