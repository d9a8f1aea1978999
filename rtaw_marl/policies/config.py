"""Parameters of the rule-based policies (the ``baselines`` config section); plain Python."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from rtaw_marl.errors import ConfigError
from rtaw_marl.utils.checks import check_fields

__all__ = ["PROPOSERS", "BaselinesConfig", "SearchConfig"]

#: Rules whose choices a search may try besides the network's (``search.propose``):
#: online rules only (never ``hindsight``, which sees the future).
PROPOSERS = ("mpdm", "rbts", "lookahead", "hungarian")


@dataclass(kw_only=True)
class BaselinesConfig:
    """Parameters of the rules evaluated by name (``policy=[...,lookahead,hindsight]``).

    Attributes:
        lookahead_horizon: MPDM decisions ``lookahead`` simulates after its own choice on
            the current queue (0: MPDM itself).
        lookahead_candidates: With more queued tasks than this, ``lookahead`` rolls
            out on the ones nearest the free robot only; ``None``: every queued task.
        batch_region: Side (cells) of a pickup region of the ``batch`` rule.
        batch_cap: Robots heading to one region before ``batch`` adds its penalty to
            the region's tasks.
        batch_penalty: That penalty, in cells of travel.
        batch_max: Most free robots ``batch`` matches in one problem.
        hindsight_horizon: Decisions of the ``hindsight`` reference's MPDM rollout over
            the real future (tasks, refills and noise).
    """

    lookahead_horizon: int = 3
    lookahead_candidates: int | None = None
    hindsight_horizon: int = 30
    batch_region: int = 8
    batch_cap: int = 4
    batch_penalty: float = 20.0
    batch_max: int = 256

    def __post_init__(self) -> None:
        check_fields(self, "baselines.")
        keys = (("lookahead_horizon", 0), ("hindsight_horizon", 0), ("batch_region", 1),
                ("batch_cap", 1), ("batch_max", 1))  # fmt: skip
        for key, low in keys:
            value = getattr(self, key)
            if isinstance(value, bool) or not isinstance(value, int) or value < low:
                raise ConfigError(f"baselines.{key} must be an integer >= {low}, got {value!r}")
        k = self.lookahead_candidates
        if k is not None and (isinstance(k, bool) or not isinstance(k, int) or k < 1):
            raise ConfigError(f"baselines.lookahead_candidates must be an integer >= 1, got {k!r}")
        if not self.batch_penalty >= 0:
            raise ConfigError(f"baselines.batch_penalty must be >= 0, got {self.batch_penalty!r}")


@dataclass(kw_only=True)
class SearchConfig:
    """``policy=search``: learned policies searched at decision time (the ``search``
    config section; :mod:`rtaw_marl.policies.search`).

    Each tried slot is given to the free robot and rolled forward ``horizon`` decisions
    on the current queue with the network choosing; the cheapest rollout wins. The
    defaults were chosen on the selection seeds (``python -m
    benchmarks.scripts.search_defaults``, docs/training.md "Search").

    Attributes:
        policy: The learned policies searched: checkpoint paths or shipped names (one or
            a list), each labelled ``<name>+search``.
        width: Slots tried per decision: the network's best ``width``.
        horizon: Decisions rolled out after each tried slot's, the network choosing.
        leaf: Weight of the critic's value of each rollout's final state (0: none).
        propose: Rules whose choices are tried too, besides the network's (one name or a
            list of :data:`PROPOSERS`; rolled out like the others, with the network
            choosing after them); ``None``: the network's slots only.
    """

    policy: Any = None
    width: int = 2
    horizon: int = 3
    leaf: float = 0.0
    propose: Any = None

    def __post_init__(self) -> None:
        check_fields(self, "search.")
        names = [] if self.propose is None else self.propose
        names = [names] if isinstance(names, str) else list(names)
        bad = [n for n in names if n not in PROPOSERS]
        if bad:
            raise ConfigError(
                f"search.propose: {bad[0]!r} is not a rule the search can try; valid: "
                f"{', '.join(PROPOSERS)}"
            )
        for key, low in (("width", 1), ("horizon", 0)):
            value = getattr(self, key)
            if isinstance(value, bool) or not isinstance(value, int) or value < low:
                raise ConfigError(f"search.{key} must be an integer >= {low}, got {value!r}")
        leaf = self.leaf
        if isinstance(leaf, bool) or not isinstance(leaf, (int, float)) or not 0 <= leaf < 1e9:
            raise ConfigError(f"search.leaf must be a number >= 0, got {leaf!r}")
        self.leaf = float(leaf)
