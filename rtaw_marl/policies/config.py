"""Parameters of the rule-based policies (the ``baselines`` config section); plain Python."""

from __future__ import annotations

from dataclasses import dataclass

from rtaw_marl.errors import ConfigError
from rtaw_marl.utils.checks import check_fields

__all__ = ["BaselinesConfig"]


@dataclass(kw_only=True)
class BaselinesConfig:
    """Parameters of the rules evaluated by name (``policy=[...,lookahead,hindsight]``).

    Attributes:
        lookahead_horizon: MPDM decisions ``lookahead`` simulates after its own choice on
            the current queue (0: MPDM itself).
        hindsight_horizon: Decisions of the ``hindsight`` reference's MPDM rollout over
            the real future (tasks, refills and noise).
    """

    lookahead_horizon: int = 3
    hindsight_horizon: int = 30

    def __post_init__(self) -> None:
        check_fields(self, "baselines.")
        for key, low in (("lookahead_horizon", 0), ("hindsight_horizon", 0)):
            value = getattr(self, key)
            if isinstance(value, bool) or not isinstance(value, int) or value < low:
                raise ConfigError(f"baselines.{key} must be an integer >= {low}, got {value!r}")
