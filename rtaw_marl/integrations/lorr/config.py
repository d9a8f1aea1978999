"""Typed options of ``rtaw-lorr`` (registered with Hydra by :mod:`rtaw_marl.config.store`)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from rtaw_marl.errors import ConfigError, unknown_name
from rtaw_marl.policies.config import BaselinesConfig
from rtaw_marl.utils.checks import at_least, check_fields

__all__ = ["LORR_DEFAULT", "OVERFLOWS", "PLANNERS", "LoRRConfig"]

#: ``policy=lorr_default``: the start kit's own scheduler (its C++ entry).
LORR_DEFAULT = "lorr_default"

#: ``planner=...``: the kit's default planner, or the own executor (``navigator=pibt``'s
#: defaults: LoRR's action model and traffic-flow guidance) under the kit's scheduler.
PLANNERS = ("default", "pibt")

#: ``overflow=...``: ``wait`` (the robots a scheduler could not serve in time wait for
#: the next timestep) or ``nearest`` (they take the nearest open task:
#: :func:`rtaw_marl.integrations.lorr.overflow.nearest_pairs`).
OVERFLOWS = ("wait", "nearest")

#: The largest value ``lifelong`` takes for a count or a time limit (a C++ ``int``).
_INT_MAX = 2**31 - 1


@dataclass(kw_only=True)
class LoRRConfig:
    """An ``rtaw-lorr`` run: schedulers inside LoRR's own simulator.

    Attributes:
        problem: The LoRR 2024 problem JSON (required unless ``build_only``), or
            ``builtin:random_32_32_20_100.json``, the one shipped with the package.
        policy: Schedulers, one ``lifelong`` run each: ``lorr_default`` (the kit's own),
            any rule of ``rtaw-eval`` but ``hindsight`` (``mpdm``, ``lookahead``,
            ``batch``, ...), ``checkpoint``, ``pretrained`` and ``matched``.
        checkpoint: Checkpoint path(s) when ``policy`` includes ``checkpoint``.
        pretrained: Shipped policy name(s) when ``policy`` includes ``pretrained``.
        matched: Learned policies (checkpoint paths or shipped names, one or a list)
            deciding every free robot of a timestep at once, when ``policy`` includes
            ``matched``: one network call, then a greedy matching on its
            log-probabilities (:mod:`rtaw_marl.policies.matched`; needs ``candidates``);
            labelled ``<name>@k<K>+matched``.
        candidates: Learned policies score only the ``K`` nearest queued tasks.
        baselines: Parameters of the rules.
        timesteps: LoRR's ``simulationTime`` (its competition runs 5,000).
        plan_time_ms: LoRR's ``planTimeLimit`` per timestep, for scheduler and planner
            together; its default planner uses all of it, so a run takes about
            ``timesteps x plan_time_ms``.
        preprocess_time_ms: LoRR's ``preprocessTimeLimit``.
        planner: ``default`` (the kit's planner) or ``pibt``: the own executor as LoRR's
            planner, with ``navigator=pibt``'s defaults, under the kit's default
            scheduler (LoRR's planner track; ``policy`` must be ``lorr_default``).
        share: The part of ``plan_time_ms`` the scheduler may use (the kit's default
            scheduler takes half); robots not served in it wait for the next timestep.
        overflow: What the robots an rtaw_marl scheduler could not serve in its share
            do: ``wait`` for the next timestep (counted as ``deferred``), or take the
            ``nearest`` open task by grid distance (counted as ``overflowed``; the
            scheduler stops at 90% of its share to leave time for it:
            :mod:`rtaw_marl.integrations.lorr.overflow`). ``pair_greedy`` serves every
            robot each timestep and ``lorr_default`` is the kit's own: neither stops.
        output: Where ``results.json`` goes; ``None``: the run folder.
        kit: The start kit's sources; ``None``: ``RTAW_LORR_KIT`` or ``../shared``.
        cache: Where builds are kept; ``None``: ``RTAW_LORR_CACHE`` or
            ``~/.cache/rtaw_marl/lorr``.
        build_only: Build (once per machine) and stop.
        resume: Keep the schedulers already in ``output`` (a stopped run with the same
            setting) and run the rest.
    """

    problem: str | None = None
    policy: Any = field(default_factory=lambda: [LORR_DEFAULT, "mpdm"])
    checkpoint: Any = None
    pretrained: Any = None
    matched: Any = None
    candidates: int | None = None
    baselines: BaselinesConfig = field(default_factory=BaselinesConfig)
    timesteps: int = 500
    plan_time_ms: int = 1000
    preprocess_time_ms: int = 30000
    share: float = 0.5
    overflow: str = "wait"
    planner: str = "default"
    output: str | None = None
    kit: str | None = None
    cache: str | None = None
    build_only: bool = False
    resume: bool = False

    def __post_init__(self) -> None:
        check_fields(self)
        at_least(self, "", 1, "timesteps")
        at_least(self, "", 1, "plan_time_ms")
        at_least(self, "", 1, "preprocess_time_ms")
        for key in ("timesteps", "plan_time_ms", "preprocess_time_ms"):
            # lifelong reads them into C++ ints: a larger value would wrap around there.
            if getattr(self, key) > _INT_MAX:
                raise ConfigError(
                    f"{key} must be <= {_INT_MAX} (a C++ int in lifelong), got {getattr(self, key)}"
                )
        if self.candidates is not None:
            at_least(self, "", 1, "candidates")
        if self.planner not in PLANNERS:
            raise ConfigError(f"planner must be one of {', '.join(PLANNERS)}, got {self.planner!r}")
        if not 0 < float(self.share) <= 1:
            raise ConfigError(f"share must be in (0, 1], got {self.share}")
        if self.overflow not in OVERFLOWS:
            raise unknown_name("overflow", self.overflow, list(OVERFLOWS))
