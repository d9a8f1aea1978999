"""Allocation policies: the classical rules, stronger hand-written rules, the hindsight
reference, and (in :mod:`.network`, needs torch) trained RTAW networks."""

from __future__ import annotations

from collections.abc import Callable

from rtaw_marl.errors import unknown_name
from rtaw_marl.policies.baselines import MPDM, RBTS, BaselinePolicy, RandomPolicy
from rtaw_marl.policies.config import BaselinesConfig
from rtaw_marl.policies.hindsight import Hindsight
from rtaw_marl.policies.lookahead import Hungarian, Lookahead
from rtaw_marl.sim.navigation import Navigator

__all__ = [
    "BASELINES",
    "MPDM",
    "RBTS",
    "BaselinePolicy",
    "BaselinesConfig",
    "Hindsight",
    "Hungarian",
    "Lookahead",
    "RandomPolicy",
    "make_baseline",
]

_Factory = Callable[[Navigator | None, float, BaselinesConfig], "BaselinePolicy | Hindsight"]

#: Every rule evaluated by name (``rtaw-eval policy=[...]``).
BASELINES: dict[str, _Factory] = {
    MPDM.name: lambda nav, scale, _: MPDM(nav, scale),
    RBTS.name: lambda nav, scale, _: RBTS(nav, scale),
    RandomPolicy.name: lambda nav, scale, _: RandomPolicy(nav, scale),
    Lookahead.name: lambda nav, scale, p: Lookahead(nav, scale, horizon=p.lookahead_horizon),
    Hungarian.name: lambda nav, scale, _: Hungarian(nav, scale),
    Hindsight.name: lambda nav, scale, p: Hindsight(p.hindsight_horizon),
}


def make_baseline(
    name: str,
    navigator: Navigator | None = None,
    scale: float = 1.0,
    params: BaselinesConfig | None = None,
) -> BaselinePolicy | Hindsight:
    """Build the rule registered as ``name``.

    Args:
        name: ``mpdm``, ``rbts``, ``random``, ``lookahead``, ``hungarian`` or ``hindsight``.
        navigator: The env's navigator (needed by rules acting on observations).
        scale: The observation length scale.
        params: Rule parameters (horizons); the defaults when ``None``.

    Raises:
        ConfigError: Unknown name; the message lists the available ones.
    """
    try:
        factory = BASELINES[name]
    except KeyError:
        raise unknown_name("policy", name, list(BASELINES)) from None
    return factory(navigator, scale, params or BaselinesConfig())
