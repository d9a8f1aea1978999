"""Typed options of ``rtaw-eval`` and ``rtaw-render`` (plain Python, registered with
Hydra by :mod:`rtaw_marl.config.store`)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from rtaw_marl.errors import ConfigError
from rtaw_marl.evaluation.best_rule import BEST, SELECTION_SEEDS
from rtaw_marl.policies.config import BaselinesConfig, SearchConfig
from rtaw_marl.sim.builder import SimGroups
from rtaw_marl.sim.inputs import seed_list, seed_value
from rtaw_marl.utils.checks import at_least, check_fields

__all__ = ["EvalConfig", "RenderConfig", "ViewConfig"]


@dataclass(kw_only=True)
class EvalConfig(SimGroups):
    """An ``rtaw-eval`` run.

    Attributes:
        policy: Policies to evaluate, by name (one or a list): ``mpdm``, ``rbts``,
            ``random``, ``lookahead``, ``hungarian``, ``batch``, ``hindsight`` (a
            reference that knows the future), ``checkpoint`` (trained files),
            ``pretrained`` (shipped policies; ``rtaw`` is its deprecated name) and
            ``search`` (learned policies searched at decision time, ``search.policy``)
            and ``matched`` (learned policies deciding a timestep's robots together).
        checkpoint: Checkpoint path(s) evaluated when ``policy`` includes ``checkpoint``.
        pretrained: Shipped policy name(s) evaluated when ``policy`` includes ``pretrained``.
        matched: Learned policies (checkpoint paths or shipped names, one or a list)
            deciding every free robot of a timestep at once, when ``policy`` includes
            ``matched``: one network call, then a greedy matching on its
            log-probabilities (:mod:`rtaw_marl.policies.matched`; needs ``candidates``);
            labelled ``<name>@k<K>+matched``.
        seeds: Episode seeds; every policy sees the same tasks for the same seed.
        compare_to: A policy name (among ``policy``'s) every other policy is also
            compared with, besides MPDM: a paired TTD difference with its interval.
            ``best``: the best rule of the setting, chosen among mpdm, rbts, lookahead,
            hungarian and batch on the selection seeds 1000-1019 (least mean TTD; most
            tasks finished in horizon episodes) and evaluated too; the seeds must then
            avoid 1000-1019.
        lower_bound: Report the assignment lower bound on TTD and each policy's gap to
            it (drain mode only); off by default: it is loose and costly at large sizes.
        output: Where ``results.json`` goes; ``None`` means the Hydra run folder. Each
            finished episode is also appended to ``<stem>.episodes.jsonl`` beside it.
        resume: Take the episodes already in that journal (a killed run with the same
            ``output`` and setting) instead of running them again.
        progress: Show a tqdm progress bar.
        torch_threads: torch intra-op threads for network policies.
        candidates: Learned policies score only the ``K`` queued tasks whose origins are
            nearest the free robot when the queue holds more (a decision then costs
            ``O(K)`` network work); ``None``: every queued task.
        baselines: Parameters of the rules (``lookahead`` and ``hindsight`` horizons).
        search: ``policy=search``: the learned policies searched at decision time
            (``search.policy``) and the search's width, horizon and leaf weight.
    """

    policy: Any = field(default_factory=lambda: ["mpdm", "rbts", "random"])
    checkpoint: Any = None
    pretrained: Any = None
    matched: Any = None
    seeds: Any = field(default_factory=lambda: [0, 1, 2, 3, 4])
    compare_to: str | None = None
    lower_bound: bool = False
    output: str | None = None
    resume: bool = False
    progress: bool = True
    torch_threads: int = 1
    candidates: int | None = None
    baselines: BaselinesConfig = field(default_factory=BaselinesConfig)
    search: SearchConfig = field(default_factory=SearchConfig)

    def __post_init__(self) -> None:
        check_fields(self)
        at_least(self, "", 1, "torch_threads")
        if self.candidates is not None:
            at_least(self, "", 1, "candidates")
        seeds = self.seeds
        if isinstance(seeds, (list, tuple)):
            if not seeds:
                raise ConfigError("seeds must name at least one seed")
        else:
            seeds = [seed_value(seeds, "seeds")]
        # Checked here, once: the command uses the list as it is.
        self.seeds = seed_list(seeds, "seeds")
        shared = sorted(set(self.seeds) & set(SELECTION_SEEDS))
        if self.compare_to == BEST and shared:
            raise ConfigError(
                f"compare_to=best chooses the best rule on seeds {SELECTION_SEEDS[0]}-"
                f"{SELECTION_SEEDS[-1]}; seed {shared[0]} cannot also be reported: "
                "evaluate on other seeds (the evaluation seeds are 0-19)"
            )


@dataclass(kw_only=True)
class RenderConfig(SimGroups):
    """An ``rtaw-render`` run: one episode of one policy, saved as an animated GIF.

    Attributes:
        policy: One policy: ``mpdm``, ``rbts``, ``random``, ``lookahead``, ``hungarian``,
            ``checkpoint``, ``pretrained``, ``search`` or ``matched``.
        checkpoint: The checkpoint path when ``policy=checkpoint``.
        pretrained: The shipped policy name when ``policy=pretrained``.
        matched: Learned policies (checkpoint paths or shipped names, one or a list)
            deciding every free robot of a timestep at once, when ``policy`` includes
            ``matched``: one network call, then a greedy matching on its
            log-probabilities (:mod:`rtaw_marl.policies.matched`; needs ``candidates``);
            labelled ``<name>@k<K>+matched``.
        seed: Episode seed.
        output: The GIF; ``None`` means ``episode.gif`` in the Hydra run folder. A name
            ending in ``.json`` writes the episode in LoRR's output format instead, for
            LoRR's viewer PlanViz (``actualPaths``, ``events``, ``tasks``; docs/lorr.md).
        fps: Frames per second.
        every: Draw every k-th time step.
        start: First time step drawn.
        stop: Last time step drawn; ``None``: the end.
        max_frames: Refuse to draw more frames than this.
        cell_px: Pixels per grid cell; ``None`` picks about 600 px across.
        torch_threads: torch intra-op threads for network policies.
        candidates: Learned policies score only the ``K`` queued tasks whose origins are
            nearest the free robot when the queue holds more (a decision then costs
            ``O(K)`` network work); ``None``: every queued task.
        baselines: Parameters of the rules (``lookahead`` and ``hindsight`` horizons).
        search: ``policy=search``: the learned policies searched at decision time
            (``search.policy``) and the search's width, horizon and leaf weight.
    """

    policy: str = "mpdm"
    checkpoint: str | None = None
    pretrained: str | None = None
    matched: Any = None
    seed: int = 0
    output: str | None = None
    fps: int = 8
    every: int = 1
    start: int = 0
    stop: int | None = None
    max_frames: int = 1000
    cell_px: int | None = None
    torch_threads: int = 1
    candidates: int | None = None
    baselines: BaselinesConfig = field(default_factory=BaselinesConfig)
    search: SearchConfig = field(default_factory=SearchConfig)

    def __post_init__(self) -> None:
        check_fields(self)
        seed_value(self.seed, "seed")
        at_least(self, "", 1, "fps", "every", "max_frames", "torch_threads")
        if self.candidates is not None:
            at_least(self, "", 1, "candidates")
        at_least(self, "", 0, "start")
        if self.stop is not None:
            at_least(self, "", 0, "stop")
        if self.cell_px is not None:
            at_least(self, "", 1, "cell_px")


@dataclass(kw_only=True)
class ViewConfig(SimGroups):
    """An ``rtaw-view`` run: one or two episodes in a self-contained HTML viewer.

    Attributes:
        policy: One policy, or two shown side by side on the same seed (names as in
            ``rtaw-eval``; ``hindsight`` and ``batch`` included).
        checkpoint: The checkpoint path when ``policy`` includes ``checkpoint``.
        pretrained: The shipped policy name when ``policy`` includes ``pretrained``.
        matched: Learned policies (checkpoint paths or shipped names, one or a list)
            deciding every free robot of a timestep at once, when ``policy`` includes
            ``matched``: one network call, then a greedy matching on its
            log-probabilities (:mod:`rtaw_marl.policies.matched`; needs ``candidates``);
            labelled ``<name>@k<K>+matched``.
        seed: Episode seed.
        schedule: Instead of playing ``policy``: one or two saved episodes in LoRR's
            output format (``rtaw-render output=*.json`` or LoRR's ``lifelong``), on the
            map of the layout options (``scenario=lorr tasks.problem=P`` for a LoRR map).
        output: The HTML file; ``None`` means ``view.html`` in the Hydra run folder.
        title: The page's title; ``None``: the policies, navigator, layout and seed.
        torch_threads: torch intra-op threads for network policies.
        candidates: Learned policies score only the ``K`` queued tasks whose origins are
            nearest the free robot when the queue holds more; ``None``: every one.
        baselines: Parameters of the rules (``lookahead`` and ``hindsight`` horizons).
        search: ``policy=search``: the learned policies searched at decision time
            (``search.policy``) and the search's width, horizon and leaf weight.
    """

    policy: Any = "mpdm"
    checkpoint: str | None = None
    pretrained: str | None = None
    matched: Any = None
    seed: int = 0
    schedule: Any = None
    output: str | None = None
    title: str | None = None
    torch_threads: int = 1
    candidates: int | None = None
    baselines: BaselinesConfig = field(default_factory=BaselinesConfig)
    search: SearchConfig = field(default_factory=SearchConfig)

    def __post_init__(self) -> None:
        check_fields(self)
        seed_value(self.seed, "seed")
        at_least(self, "", 1, "torch_threads")
        if self.candidates is not None:
            at_least(self, "", 1, "candidates")
        for key in ("policy", "schedule"):
            value = getattr(self, key)
            values = list(value) if isinstance(value, (list, tuple)) else [value]
            if value is None and key == "schedule":
                continue
            if not 1 <= len(values) <= 2 or not all(isinstance(v, str) and v for v in values):
                raise ConfigError(
                    f"{key} must be one name or a list of two (side by side), got {value!r}"
                )
