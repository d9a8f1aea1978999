"""A training run's last word: does its checkpoint beat the setting's best rule?

Checkpoints are chosen on the selection seeds, and so is the best rule (the
:class:`~rtaw_marl.training.evaluator.Evaluator`'s bar); both then play the evaluation
seeds 0-19, which nothing in the run has seen, and the paired difference decides, with
its 95% interval: *beats it* when the interval is above zero, *loses to it* when below,
*does not beat it* (a tie within the noise) otherwise. Episodes are judged as everywhere
else: by total travel delay, or by tasks finished in fixed-horizon episodes.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from rtaw_marl.errors import missing_extra

# Without the training extra: one error that names it (errors.missing_extra), no traceback
# of a bare ModuleNotFoundError.
try:
    from tqdm import tqdm
except ModuleNotFoundError as exc:
    raise missing_extra(exc, __name__, "train") from None

from rtaw_marl.evaluation.evaluate import evaluate
from rtaw_marl.evaluation.metric_goals import metric_goal
from rtaw_marl.evaluation.stats import PairedDiff, paired_difference
from rtaw_marl.policies import BaselinesConfig, make_baseline
from rtaw_marl.policies.network import load_policy
from rtaw_marl.scenarios import EVAL_SEEDS
from rtaw_marl.sim.builder import SimSpec, build_sim
from rtaw_marl.sim.inputs import seed_span

__all__ = ["Verdict", "judge"]


@dataclass(frozen=True)
class Verdict:
    """The checkpoint against the best rule on the evaluation seeds.

    Attributes:
        checkpoint: The checkpoint file judged.
        rule: The best rule, chosen on ``chosen_on``.
        chosen_on: The selection seeds the rule (and the checkpoint) were chosen on.
        metric: ``ttd`` or ``tasks_finished``.
        seeds: The evaluation seeds played.
        diff: The paired difference, positive when the checkpoint is better.
    """

    checkpoint: Path
    rule: str
    chosen_on: tuple[int, ...]
    metric: str
    seeds: tuple[int, ...]
    diff: PairedDiff

    @property
    def outcome(self) -> str:
        """``beats``, ``loses to`` or ``does not beat`` (within the noise)."""
        if not self.diff.significant:
            return "does not beat"
        return "beats" if self.diff.mean > 0 else "loses to"

    def line(self) -> str:
        """One line: what was compared where, both means, the gain with its interval."""
        d = self.diff
        what = "TTD" if self.metric == "ttd" else "tasks finished"
        interval = f" [{d.pct_low:+.1f}, {d.pct_high:+.1f}]" if d.pct_low is not None else " [n/a]"
        noise = " (a tie within the noise)" if self.outcome == "does not beat" else ""
        return (
            f"verdict: {self.checkpoint.name} {self.outcome} {self.rule}{noise} (the best rule "
            f"on selection seeds {seed_span(self.chosen_on)}) on evaluation seeds "
            f"{seed_span(self.seeds)}: {what} {d.other_mean:,.1f} against {d.baseline_mean:,.1f}, "
            f"a gain of {d.pct:+.1f}%{interval} (paired, {d.confidence:.0%} interval)"
        )

    def as_dict(self) -> dict[str, Any]:
        """Plain values (``verdict.json`` in the run folder)."""
        return {
            "checkpoint": str(self.checkpoint), "rule": self.rule,
            "chosen_on": list(self.chosen_on), "metric": self.metric,
            "seeds": list(self.seeds), "outcome": self.outcome, "line": self.line(),
            "difference": self.diff.as_dict(),
        }  # fmt: skip


def judge(
    spec: SimSpec,
    checkpoint: Path,
    rule: str,
    chosen_on: Sequence[int],
    *,
    metric: str = "ttd",
    candidates: int | None = None,
    seeds: Sequence[int] = EVAL_SEEDS,
    progress: bool = False,
) -> Verdict:
    """Play ``checkpoint``'s greedy policy and ``rule`` on ``seeds`` of ``spec``.

    Args:
        spec: The setting (the run's selection setting).
        checkpoint: The checkpoint to judge (the run's ``best.pt``).
        rule: The best rule, chosen on ``chosen_on``.
        chosen_on: The selection seeds, for the line.
        metric: ``ttd`` (lower is better) or ``tasks_finished`` (higher is better).
        candidates: The policy's and ``lookahead``'s candidate tasks, as in training.
        seeds: Evaluation seeds (0-19).
        progress: Show a progress bar over the seeds (the run's last phase).

    Returns:
        The :class:`Verdict`.
    """
    params = BaselinesConfig(lookahead_candidates=candidates)
    policies = {
        rule: make_baseline(rule, params=params),
        "checkpoint": load_policy(checkpoint, name="checkpoint", candidates=candidates,
                                  torch_threads=None),
    }  # fmt: skip
    bar = tqdm(total=len(seeds), desc="verdict", unit="seed", disable=not progress)
    with bar:
        results = evaluate(
            build_sim(spec), policies, list(seeds), on_seed=lambda done, _: bar.update(done - bar.n)
        )  # fmt: skip
    goal = metric_goal(metric)
    if goal is None:
        raise ValueError(f"a verdict is on a metric with a better side, not {metric!r}")
    diff = paired_difference(results[rule][metric], results["checkpoint"][metric], positive=goal)
    return Verdict(Path(checkpoint), rule, tuple(chosen_on), metric, tuple(seeds), diff)
