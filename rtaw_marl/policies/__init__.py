"""Allocation policies: the classical baselines (and, later, learned policies)."""

from __future__ import annotations

from rtaw_marl.errors import unknown_name
from rtaw_marl.policies.baselines import MPDM, RBTS, BaselinePolicy, RandomPolicy
from rtaw_marl.sim.navigation import Navigator

__all__ = ["BASELINES", "MPDM", "RBTS", "BaselinePolicy", "RandomPolicy", "make_baseline"]

BASELINES: dict[str, type[BaselinePolicy]] = {
    MPDM.name: MPDM,
    RBTS.name: RBTS,
    RandomPolicy.name: RandomPolicy,
}


def make_baseline(
    name: str, navigator: Navigator | None = None, scale: float = 1.0
) -> BaselinePolicy:
    """Build the baseline registered as ``name``.

    Raises:
        ConfigError: Unknown name; the message lists the available ones.
    """
    try:
        cls = BASELINES[name]
    except KeyError:
        raise unknown_name("policy", name, list(BASELINES)) from None
    return cls(navigator=navigator, scale=scale)
