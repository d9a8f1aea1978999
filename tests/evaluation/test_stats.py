"""Paired statistics over seeds: t-intervals, percent, significance, hindsight share, and
the table and JSON built from them."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from scipy import stats as sps

from rtaw_marl.evaluation import (
    comparisons,
    format_table,
    hindsight_share,
    json_safe,
    mean_ci,
    paired_difference,
)

pytestmark = pytest.mark.unit

BASE = [10.0, 12.0, 11.0, 13.0, 9.0]
OTHER = [9.0, 11.5, 9.0, 12.0, 8.5]  # differences 1, 0.5, 2, 1, 0.5


def test_paired_difference_matches_hand_computed_t_interval() -> None:
    """Differences 1, .5, 2, 1, .5: mean 1, sd sqrt(.375), t(.975, 4) = 2.7764."""
    diff = paired_difference(BASE, OTHER)
    sd = math.sqrt(((0.0**2) + 0.5**2 + 1.0**2 + 0.0**2 + 0.5**2) / 4)
    half = 2.7764451051977987 * sd / math.sqrt(5)
    assert diff.n == 5
    assert diff.mean == pytest.approx(1.0)
    assert diff.sd == pytest.approx(sd)
    assert (diff.low, diff.high) == pytest.approx((1.0 - half, 1.0 + half))
    assert diff.baseline_mean == pytest.approx(11.0)
    assert diff.other_mean == pytest.approx(10.0)
    assert diff.pct == pytest.approx(100 / 11)
    assert (diff.pct_low, diff.pct_high) == pytest.approx(
        (100 * (1 - half) / 11, 100 * (1 + half) / 11)
    )
    assert diff.significant


def test_paired_difference_agrees_with_scipy() -> None:
    """The interval is scipy's t-interval of the differences; the paired t-test agrees."""
    rng = np.random.default_rng(3)
    base = rng.normal(100, 10, 8)
    other = base - rng.normal(2, 3, 8)
    diff = paired_difference(base, other, confidence=0.9)
    d = base - other
    low, high = sps.t.interval(0.9, len(d) - 1, loc=d.mean(), scale=sps.sem(d))
    assert (diff.low, diff.high) == pytest.approx((low, high))
    p_value = sps.ttest_rel(base, other).pvalue
    # At 90% the interval excludes 0 exactly when the two-sided p-value is below 0.1.
    assert diff.significant == (p_value < 0.1)


def test_paired_difference_is_antisymmetric() -> None:
    """Swapping the two policies flips the sign of the difference and of the interval."""
    ab, ba = paired_difference(BASE, OTHER), paired_difference(OTHER, BASE)
    assert ba.mean == pytest.approx(-ab.mean)
    assert (ba.low, ba.high) == pytest.approx((-ab.high, -ab.low))
    assert ba.sd == pytest.approx(ab.sd)
    assert ba.significant == ab.significant


def test_pairing_is_what_makes_it_significant() -> None:
    """A shared per-seed offset cancels: tiny consistent gains on spread-out episodes are
    significant paired, while an unpaired comparison of the means would not see them."""
    episodes = np.array([100.0, 300.0, 200.0, 500.0, 50.0])
    better = episodes - np.array([1.0, 1.2, 0.9, 1.1, 1.0])
    diff = paired_difference(episodes, better)
    assert diff.significant
    assert sps.ttest_ind(episodes, better).pvalue > 0.9


def test_not_significant_when_interval_straddles_zero() -> None:
    diff = paired_difference([10.0, 10.0, 10.0, 10.0], [9.0, 11.0, 9.5, 10.5])
    assert diff.low is not None
    assert diff.high is not None
    assert diff.low < 0 < diff.high
    assert not diff.significant


def test_identical_vectors_give_a_zero_width_interval_and_no_significance() -> None:
    diff = paired_difference(BASE, BASE)
    assert (diff.mean, diff.sd, diff.low, diff.high) == (0.0, 0.0, 0.0, 0.0)
    assert (diff.pct, diff.pct_low, diff.pct_high) == (0.0, 0.0, 0.0)
    assert not diff.significant


def test_constant_nonzero_difference_is_significant() -> None:
    """Deterministic episodes: the same gain on every seed, a zero-width interval."""
    diff = paired_difference([5.0, 5.0, 5.0], [4.0, 4.0, 4.0])
    assert (diff.low, diff.high) == (1.0, 1.0)
    assert diff.pct == pytest.approx(20.0)
    assert diff.significant


def test_one_seed_has_no_interval_and_no_nan() -> None:
    diff = paired_difference([22.7], [18.5])
    assert diff.n == 1
    assert diff.mean == pytest.approx(4.2)
    assert diff.pct == pytest.approx(100 * 4.2 / 22.7)
    assert (diff.sd, diff.low, diff.high, diff.pct_low, diff.pct_high) == (None,) * 5
    assert not diff.significant
    data = diff.as_dict()
    assert (data["ci"], data["pct_ci"], data["sd_diff"]) == (None, None, None)
    json.dumps(data, allow_nan=False)


def test_zero_baseline_mean_has_no_percent() -> None:
    diff = paired_difference([0.0, 0.0], [1.0, 2.0])
    assert (diff.pct, diff.pct_low, diff.pct_high) == (None, None, None)
    json.dumps(diff.as_dict(), allow_nan=False)


def test_as_dict_round_trips_through_strict_json() -> None:
    data = json.loads(json.dumps(paired_difference(BASE, OTHER).as_dict(), allow_nan=False))
    assert data["n"] == 5
    assert data["confidence"] == 0.95
    assert data["mean_diff"] == pytest.approx(1.0)
    assert data["ci"][0] < data["mean_diff"] < data["ci"][1]
    assert data["pct_ci"][0] < data["pct"] < data["pct_ci"][1]
    assert data["significant"] is True
    assert "t-interval" in data["method"]


@pytest.mark.parametrize(
    ("base", "other", "confidence", "message"),
    [
        ([1.0, 2.0], [1.0], 0.95, "differ in length"),
        ([], [], 0.95, "non-empty"),
        ([1.0, math.nan], [1.0, 2.0], 0.95, "non-finite"),
        ([1.0, 2.0], [1.0, 2.0], 1.0, "confidence must be in"),
    ],
)
def test_bad_input_raises(
    base: list[float], other: list[float], confidence: float, message: str
) -> None:
    with pytest.raises(ValueError, match=message):
        paired_difference(base, other, confidence)


def test_mean_ci() -> None:
    values = [1.0, 2.0, 3.0, 4.0]
    mean, half = mean_ci(values)
    low, high = sps.t.interval(0.95, 3, loc=2.5, scale=sps.sem(values))
    assert mean == 2.5
    assert half == pytest.approx((high - low) / 2)
    assert mean_ci([7.0]) == (7.0, None)


def test_hindsight_share_point_and_interval() -> None:
    """Gains over MPDM: hindsight 10 per seed, the policy 4, 5, 6: share 0.5, and the
    residuals a - 0.5 b are -1, 0, 1: half-width t(.975, 2) * 1 / sqrt(3) / 10."""
    mpdm = [100.0, 110.0, 120.0]
    hindsight = [90.0, 100.0, 110.0]
    policy = [96.0, 105.0, 114.0]
    share = hindsight_share(mpdm, policy, hindsight)
    assert share is not None
    assert share.share == pytest.approx(0.5)
    half = sps.t.ppf(0.975, 2) / math.sqrt(3) / 10
    assert (share.low, share.high) == pytest.approx((0.5 - half, 0.5 + half))
    assert hindsight_share(mpdm, mpdm, hindsight).share == 0.0
    assert hindsight_share(mpdm, hindsight, hindsight).share == pytest.approx(1.0)
    json.dumps(share.as_dict(), allow_nan=False)


def test_hindsight_share_none_when_hindsight_does_not_beat_mpdm() -> None:
    assert hindsight_share([10.0, 10.0], [9.0, 9.0], [10.0, 10.0]) is None
    assert hindsight_share([10.0, 10.0], [9.0, 9.0], [11.0, 12.0]) is None


def test_hindsight_share_one_seed() -> None:
    share = hindsight_share([10.0], [8.0], [6.0])
    assert share is not None
    assert (share.share, share.low, share.high) == (0.5, None, None)
    assert share.as_dict()["ci"] is None


def _metrics(ttd: list[float]) -> dict[str, list[float]]:
    return {"ttd": ttd, "makespan": ttd, "wait_max": ttd, "wall_time_s": [0.1] * len(ttd)}


RESULTS = {
    "mpdm": _metrics([100.0, 110.0, 120.0]),
    "rbts": _metrics([96.0, 105.0, 114.0]),
    "hindsight": _metrics([90.0, 100.0, 110.0]),
}


def test_comparisons_block() -> None:
    """Every policy against mpdm and compare_to, never itself; hindsight share when
    hindsight and mpdm were evaluated."""
    block = comparisons(RESULTS, compare_to="rbts")
    assert set(block["mpdm"]["vs"]) == {"rbts"}
    assert set(block["rbts"]["vs"]) == {"mpdm"}
    assert set(block["hindsight"]["vs"]) == {"mpdm", "rbts"}
    assert (
        block["rbts"]["vs"]["mpdm"]
        == paired_difference(RESULTS["mpdm"]["ttd"], RESULTS["rbts"]["ttd"]).as_dict()
    )
    assert block["rbts"]["hindsight_share"]["share"] == pytest.approx(0.5)
    no_hindsight = comparisons({k: v for k, v in RESULTS.items() if k != "hindsight"})
    assert "hindsight_share" not in no_hindsight["rbts"]
    assert comparisons({"rbts": RESULTS["rbts"]}) == {"rbts": {"vs": {}}}


def test_format_table_columns_cells_and_legend() -> None:
    table = format_table(RESULTS, compare_to="rbts", lower_bound=[80.0, 85.0, 90.0])
    lines = table.splitlines()
    header = lines[0]
    assert "TTD ± 95% CI" in header
    for column in ("TTD vs MPDM", "TTD vs RBTS", "hindsight share", "gap to bound"):
        assert column in header
    rows = {line.split(" | ")[0].strip("| "): line for line in lines[2:-1]}
    assert set(rows) == {
        "lower bound",
        "mpdm",
        "rbts",
        "hindsight (reference: knows the future)",
    }
    diff = paired_difference(RESULTS["mpdm"]["ttd"], RESULTS["rbts"]["ttd"])
    cell = f"{diff.pct:+.1f}% [{diff.pct_low:+.1f}, {diff.pct_high:+.1f}]*"
    assert cell in rows["rbts"]
    assert "50% [" in rows["rbts"]  # the hindsight share
    legend = lines[-1]
    assert not legend.startswith("|")
    assert "95% Student t-intervals over 3 seeds" in legend
    assert "* = interval excludes 0" in legend
    assert "hindsight share" in legend


def test_format_table_without_mpdm_or_with_one_seed() -> None:
    table = format_table({"rbts": _metrics([1.0, 2.0])})
    assert "vs" not in table.splitlines()[0]
    one = format_table({"mpdm": _metrics([10.0]), "rbts": _metrics([8.0])})
    assert "+20.0% [n/a]" in one
    assert "1 seed" in one.splitlines()[-1]
    assert "*" not in one


def test_json_safe_replaces_non_finite() -> None:
    data = {"a": [1.0, math.nan, math.inf], "b": np.float64(2.5), "c": (np.int64(3),)}
    assert json_safe(data) == {"a": [1.0, None, None], "b": 2.5, "c": [3]}
    json.dumps(json_safe(data), allow_nan=False)
