"""Which way is better for each per-episode metric: the one place that says so.

Every reader that compares two policies on a metric (``rtaw-eval``'s table legend,
``rtaw-results --metric``) asks here, so the sign of a comparison and its wording
follow one fact:

- lower is better: ``ttd``, ``makespan``, ``idle_mean``, ``idle_max``, ``wait_mean``,
  ``wait_max``, ``gap_pct`` (above the TTD lower bound) and ``wall_time_s``;
- higher is better: ``tasks_finished`` (the throughput of a ``horizon`` episode);
- neither: every other metric (``task_length``, ``tasks_served``, ``decisions`` and
  the executors' counters such as ``planning_calls`` or ``evacuations``): a difference
  says more or less, never better or worse.

A comparison's difference is positive when the other policy is better (``baseline -
other`` for a lower-is-better metric, ``other - baseline`` for a higher-is-better one)
and, for a metric with no better side, when it has more (``other - baseline``); in
percent of the baseline's mean either way
(:func:`~rtaw_marl.evaluation.stats.paired_difference`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from types import MappingProxyType
from typing import Final, Literal

from rtaw_marl.evaluation.stats import PairedDiff, paired_difference

__all__ = [
    "GOALS",
    "Goal",
    "difference_wording",
    "metric_difference",
    "metric_goal",
    "metric_label",
]

Goal = Literal["lower", "higher"]

#: The metrics with a better side; any other metric has none.
GOALS: Final[Mapping[str, Goal]] = MappingProxyType(
    {
        "ttd": "lower",
        "makespan": "lower",
        "idle_mean": "lower",
        "idle_max": "lower",
        "wait_mean": "lower",
        "wait_max": "lower",
        "gap_pct": "lower",
        "wall_time_s": "lower",
        "tasks_finished": "higher",
    }
)

#: How a metric is written in a table header or an axis label, where not as its key.
_LABELS: Final[Mapping[str, str]] = MappingProxyType({"ttd": "TTD"})


def metric_goal(metric: str) -> Goal | None:
    """``"lower"`` or ``"higher"``: which way ``metric`` is better; None: neither."""
    return GOALS.get(metric)


def metric_label(metric: str) -> str:
    """``metric`` as a header or axis label shows it (``TTD``; other names as they are)."""
    return _LABELS.get(metric, metric)


def metric_difference(
    metric: str, baseline: Sequence[float], other: Sequence[float], confidence: float = 0.95
) -> PairedDiff:
    """The paired comparison of ``other`` with ``baseline`` on ``metric``, positive when
    ``other`` is better (or, for a metric with no better side, higher).

    Raises:
        ValueError: Different lengths, empty or non-finite values, or a confidence
            outside (0, 1).
    """
    positive: Goal = "lower" if metric_goal(metric) == "lower" else "higher"
    return paired_difference(baseline, other, confidence, positive=positive)


def difference_wording(metric: str) -> tuple[str, str]:
    """What a comparison's ``+`` means for ``metric``: ``("TTD below", "+ = better")``,
    ``("tasks_finished above", "+ = better")``, or for a metric with no better side
    ``("decisions above", "+ = more")``."""
    goal = metric_goal(metric)
    side = "below" if goal == "lower" else "above"
    return f"{metric_label(metric)} {side}", "+ = better" if goal is not None else "+ = more"
