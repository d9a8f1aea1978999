"""Which way each metric is better, said once: the sign of a comparison and its wording
follow it (lower TTD, more tasks finished; more decisions is neither)."""

from __future__ import annotations

import pytest

from rtaw_marl.evaluation.metric_goals import (
    difference_wording,
    metric_difference,
    metric_goal,
    metric_label,
)
from rtaw_marl.evaluation.report import legend
from rtaw_marl.evaluation.stats import paired_difference

pytestmark = pytest.mark.unit

BASE = [10.0, 12.0, 11.0]
MORE = [12.0, 14.5, 12.5]  # per seed +2, +2.5, +1.5 over BASE: mean +2, 2/11 of BASE's mean


@pytest.mark.parametrize(
    ("metric", "goal", "sign"),
    [("ttd", "lower", -1), ("makespan", "lower", -1), ("wait_max", "lower", -1),
     ("tasks_finished", "higher", 1), ("decisions", None, 1), ("planning_calls", None, 1)],
)  # fmt: skip
def test_more_is_better_only_where_the_metric_says(
    metric: str, goal: str | None, sign: int
) -> None:
    """A policy with more of the metric than the baseline: negative for a lower-is-better
    metric (it is worse), positive for one where more is better or neither is."""
    assert metric_goal(metric) == goal
    diff = metric_difference(metric, BASE, MORE)
    assert diff.mean == pytest.approx(sign * 2.0)
    assert diff.pct == pytest.approx(sign * 200 / 11)
    assert diff.baseline_mean == pytest.approx(11.0)
    assert diff.other_mean == pytest.approx(13.0)
    assert diff.significant


def test_higher_is_the_lower_difference_turned_round() -> None:
    lower = paired_difference(BASE, MORE)
    higher = paired_difference(BASE, MORE, positive="higher")
    assert higher.mean == pytest.approx(-lower.mean)
    assert (higher.low, higher.high) == pytest.approx((-lower.high, -lower.low))
    assert (higher.pct_low, higher.pct_high) == pytest.approx((-lower.pct_high, -lower.pct_low))
    assert higher.sd == pytest.approx(lower.sd)
    with pytest.raises(ValueError, match="positive must be 'lower' or 'higher'"):
        paired_difference(BASE, MORE, positive="up")  # type: ignore[arg-type]


def test_the_wording_follows_the_goal() -> None:
    assert metric_label("ttd") == "TTD"
    assert metric_label("makespan") == "makespan"
    assert difference_wording("ttd") == ("TTD below", "+ = better")
    assert difference_wording("tasks_finished") == ("tasks_finished above", "+ = better")
    assert difference_wording("decisions") == ("decisions above", "+ = more")


def test_rtaw_evals_legend_is_as_it_was() -> None:
    assert legend(5, 0.95, ["mpdm"], False, "mpdm") == (
        "± and [low, high]: 95% Student t-intervals over 5 seeds; vs X: TTD below X's, "
        "paired per seed, in % of X's mean (+ = better); * = interval excludes 0"
    )
    assert "vs X: tasks_finished above X's, paired per seed, in % of X's mean (+ = better)" in (
        legend(5, 0.95, ["mpdm"], False, "mpdm", "tasks_finished")
    )
