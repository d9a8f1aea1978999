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

from rtaw_marl.errors import ConfigError, missing_extra, unknown_name
from rtaw_marl.policies.base import Policy, simulator_of
from rtaw_marl.policies.baselines import MPDM, RBTS, BaselinePolicy, RandomPolicy
from rtaw_marl.policies.batch import BatchAssignment
from rtaw_marl.policies.config import BaselinesConfig
from rtaw_marl.policies.hindsight import Hindsight
from rtaw_marl.policies.lookahead import Hungarian, Lookahead
from rtaw_marl.sim.distances import DistanceModel

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
    "Lookahead",
    "NetworkPolicy",
    "Policy",
    "RandomPolicy",
    "load_policy",
    "make_baseline",
]

_Factory = Callable[[DistanceModel | None, float, BaselinesConfig], "BaselinePolicy | Hindsight"]

#: Every rule evaluated by name (``rtaw-eval policy=[...]``).
BASELINES: dict[str, _Factory] = {
    MPDM.name: lambda nav, scale, _: MPDM(nav, scale),
    RBTS.name: lambda nav, scale, _: RBTS(nav, scale),
    RandomPolicy.name: lambda nav, scale, _: RandomPolicy(nav, scale),
    Lookahead.name: lambda nav, scale, p: Lookahead(
        nav, scale, horizon=p.lookahead_horizon, candidates=p.lookahead_candidates
    ),
    Hungarian.name: lambda nav, scale, _: Hungarian(nav, scale),
    BatchAssignment.name: lambda nav, scale, p: BatchAssignment(
        nav,
        scale,
        region=p.batch_region,
        cap=p.batch_cap,
        penalty=p.batch_penalty,
        max_batch=p.batch_max,
    ),
    Hindsight.name: lambda nav, scale, p: Hindsight(p.hindsight_horizon),
}

#: Names served lazily from :mod:`.network` (torch).
_NETWORK = ("NetworkPolicy", "load_policy")


def make_baseline(
    name: str,
    navigator: DistanceModel | None = None,
    scale: float = 1.0,
    params: BaselinesConfig | None = None,
    *,
    env: Any = None,
) -> BaselinePolicy | Hindsight:
    """Build the rule registered as ``name``.

    Args:
        name: ``mpdm``, ``rbts``, ``random``, ``lookahead``, ``hungarian``, ``batch``
            or ``hindsight``.
        navigator: The env's navigator (needed by rules acting on observations).
        scale: The observation length scale.
        params: Rule parameters (horizons); the defaults when ``None``.
        env: A PettingZoo or Gymnasium warehouse env (or its ``WarehouseSim``): the rule
            takes its navigator, scale and completion noise (``BaselinePolicy.bind``), so
            that ``act(obs)`` on its observations is exactly ``act_sim``. Instead of
            ``navigator`` and ``scale``.

    Raises:
        ConfigError: Unknown name (the message lists the available ones), or ``env``
            given together with ``navigator``.
    """
    try:
        factory = BASELINES[name]
    except KeyError:
        raise unknown_name("policy", name, list(BASELINES)) from None
    if env is None:
        return factory(navigator, scale, params or BaselinesConfig())
    if navigator is not None:
        raise ConfigError("make_baseline: give env or navigator/scale, not both")
    sim = simulator_of(env)
    policy = factory(sim.navigator, sim.layout.scale, params or BaselinesConfig())
    return policy.bind(sim) if isinstance(policy, BaselinePolicy) else policy


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
