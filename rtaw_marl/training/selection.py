"""A second selection stage: a run's candidate checkpoints scored on fresh selection seeds.

Training's evaluations (the first stage, ``selection.seeds``: 10 seeds of one setting) pick
the best of many evaluations. The winner's gain there is biased upwards, the more so the
flatter the curve (the winner's curse): the generalist's best of 31 evaluations was +2.2%
over lookahead on its selection seeds and -2.1% on the evaluation seeds. The second stage
plays each candidate (``checkpoints/top/*.pt`` kept by ``selection.keep``, else ``best.pt``
and ``last.pt``) and the reference rule on *fresh* selection seeds
(:data:`SECOND_STAGE_SEEDS`, disjoint from the first stage's), over several settings,
and picks the candidate with the largest pooled paired gain. With few candidates and
many episodes its gain is the estimate to report beside the evaluation seeds'.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from rtaw_marl.errors import ConfigError
from rtaw_marl.evaluation.evaluate import evaluate
from rtaw_marl.evaluation.stats import PairedDiff, pooled_difference
from rtaw_marl.models.checkpoint import load_checkpoint
from rtaw_marl.policies import make_baseline
from rtaw_marl.policies.network import load_policy
from rtaw_marl.scenarios.mix import member_spec
from rtaw_marl.sim.builder import build_sim
from rtaw_marl.sim.inputs import SELECTION_SEEDS, seed_list

__all__ = ["SECOND_STAGE_SEEDS", "StageResult", "run_candidates", "second_stage"]

#: The second stage's seeds: selection seeds the first stage (1000-1009) never plays.
SECOND_STAGE_SEEDS = tuple(range(1100, 1140))


@dataclass(frozen=True)
class StageResult:
    """What the second stage measured.

    Attributes:
        gains: Per candidate, the paired TTD gain over the reference pooled over the
            settings: ``mean``, ``low`` and ``high`` in percent of each setting's
            reference mean (:func:`~rtaw_marl.evaluation.stats.pooled_difference`;
            ``n`` counts episodes).
        chosen: The candidate with the largest mean gain (ties: the first listed).
        reference: The rule compared with.
        settings: The settings (mix member names) played.
        seeds: The seeds played in each setting.
        ttd: ``{setting: {policy: [TTD per seed]}}``.
    """

    gains: dict[str, PairedDiff]
    chosen: str
    reference: str
    settings: tuple[str, ...]
    seeds: tuple[int, ...]
    ttd: dict[str, dict[str, list[float]]]

    def as_dict(self) -> dict[str, Any]:
        """A JSON-ready record (stored in the shipped checkpoint)."""
        return {
            "chosen": self.chosen,
            "reference": self.reference,
            "settings": list(self.settings),
            "seeds": [self.seeds[0], self.seeds[-1] + 1],
            # A pooled difference is in percent already: its mean, low and high.
            "gains_pct": {name: [g.mean, g.low, g.high] for name, g in self.gains.items()},
        }


def run_candidates(run_dir: Path) -> dict[str, Path]:
    """A run's candidates: ``checkpoints/top/*.pt`` (``selection.keep``), else ``best.pt`` and
    ``last.pt`` (one when they hold the same frames), labelled ``frames_<n>``."""
    folder = Path(run_dir) / "checkpoints"
    files = sorted((folder / "top").glob("*.pt")) or [folder / "best.pt", folder / "last.pt"]
    out: dict[str, Path] = {}
    for path in files:
        if not path.is_file():
            raise ConfigError(f"{path} is missing: is {run_dir} a finished training run?")
        out.setdefault(f"frames_{int(load_checkpoint(path)['frames'])}", path)
    return out


def _play(setting: str, candidates: Mapping[str, Path], reference: str, seeds: Sequence[int]):
    sim = build_sim(member_spec(setting))
    policies: dict[str, Any] = {reference: make_baseline(reference, env=sim)}
    for label, path in candidates.items():
        policies[label] = load_policy(path, name=label)
    return {name: r["ttd"] for name, r in evaluate(sim, policies, list(seeds)).items()}


def second_stage(
    candidates: Mapping[str, Path],
    settings: Sequence[str],
    seeds: Sequence[int] = SECOND_STAGE_SEEDS,
    first_stage: Sequence[int] = (),
    reference: str = "lookahead",
    workers: int = 1,
) -> StageResult:
    """Score every candidate against ``reference`` on fresh selection seeds.

    Args:
        candidates: Checkpoints by label (:func:`run_candidates`).
        settings: Mix member names (:func:`~rtaw_marl.scenarios.mix.member_spec`).
        seeds: The second stage's seeds: selection seeds (>= 1000), distinct.
        first_stage: The seeds the first stage selected on; ``seeds`` must avoid them.
        reference: The rule every candidate is compared with.
        workers: Settings played at once (processes).

    Raises:
        ConfigError: No candidate or setting, or seeds that are evaluation seeds or
            were already used for selection.
    """
    seeds = tuple(seed_list(list(seeds), "second-stage seeds"))
    if not candidates or not settings:
        raise ConfigError("the second stage needs at least one candidate and one setting")
    low = [s for s in seeds if s < SELECTION_SEEDS]
    reused = sorted(set(seeds) & set(first_stage))
    if low or reused:
        bad = low or reused
        raise ConfigError(
            f"second-stage seeds {bad[:5]} are "
            + ("evaluation seeds" if low else "the first stage's selection seeds")
            + ": the second stage needs fresh selection seeds (>= 1000)"
        )
    jobs = [(s, dict(candidates), reference, seeds) for s in settings]
    if workers > 1:
        with ProcessPoolExecutor(min(workers, len(jobs))) as pool:
            played = list(pool.map(_play, *zip(*jobs, strict=True)))
    else:
        played = [_play(*job) for job in jobs]
    ttd = dict(zip(settings, played, strict=True))
    gains = {}
    for label in candidates:
        pooled = pooled_difference([(t[reference], t[label]) for t in ttd.values()])
        assert pooled is not None  # settings is not empty
        gains[label] = pooled
    chosen = max(gains, key=lambda k: gains[k].mean)
    return StageResult(gains, chosen, reference, tuple(settings), seeds, ttd)
