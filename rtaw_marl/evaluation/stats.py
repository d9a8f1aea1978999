"""Uncertainty of policy comparisons over seeds.

``rtaw-eval`` runs every policy on the same seeds, and a seed fixes the whole episode
input (task stream, arrival times, completion noise). Two policies' TTDs on one seed
are therefore *paired* observations, and the question "is B better than A?" is answered
from the per-seed differences ``d_i = ttd_A(seed_i) - ttd_B(seed_i)``:

- mean difference ``d̄``, its standard error ``s_d / sqrt(n)``, and the paired Student
  t-interval ``d̄ ± t_{(1+c)/2, n-1} * s_d / sqrt(n)`` at confidence ``c`` (95%).

Why paired: most of the seed-to-seed spread of TTD comes from the episode (some task
streams are harder than others), and it hits both policies alike. Differencing per seed
cancels it, so the paired interval is much narrower than one built from two independent
means (Welch) on the same runs, and it is the honest one for a common-random-numbers
design. It assumes the per-seed differences are roughly normal, or enough seeds for the
t approximation; with 5 seeds treat it as an indication, not a verdict.

The interval is also given in percent of the baseline's mean TTD (``100 * d̄ /
mean(A)``, the bounds scaled alike). The scaling treats the baseline mean as a known
constant; its own uncertainty is not propagated. That keeps the percent interval
exactly the difference interval in other units, and the relative uncertainty of a mean
TTD over seeds is usually small next to that of a difference of a few percent.

A comparison is *significant* when its interval excludes 0 (the paired t-test's p-value
is below ``1 - confidence``). When every per-seed difference is the same (deterministic
episodes) the interval has zero width and any nonzero difference is significant: this
is what the data says, not a rounding artifact. With one seed there is no interval: the
fields are ``None`` (``null`` in JSON), never NaN.

:func:`hindsight_share` measures how much of the gain of a policy that knows the future
(``hindsight``) over MPDM another policy captures: ``(mean(mpdm) - mean(policy)) /
(mean(mpdm) - mean(hindsight))``. Its interval is the delta method for a ratio of paired
means: with ``R`` the share and per-seed residuals ``z_i = a_i - R b_i`` (``a_i``, ``b_i``
the per-seed gains of the policy and of hindsight over MPDM), ``R ± t * s_z / (sqrt(n)
|b̄|)``; reliable only when hindsight's gain is large next to its seed-to-seed spread.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
from scipy import stats as sps

__all__ = [
    "HindsightShare",
    "PairedDiff",
    "hindsight_share",
    "mean_ci",
    "paired_difference",
    "pooled_difference",
    "pooled_hindsight_share",
]

#: Name of the method in the JSON output, so a results file says how it was computed.
METHOD = "paired Student t-interval over seeds"


def _as_array(values: Sequence[float], what: str) -> np.ndarray:
    arr = np.asarray(values, dtype=np.float64)
    if arr.ndim != 1 or arr.size == 0:
        raise ValueError(f"{what} must be a non-empty sequence of numbers")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{what} has a non-finite value: {values}")
    return arr


def _check_confidence(confidence: float) -> None:
    if not 0.0 < confidence < 1.0:
        raise ValueError(f"confidence must be in (0, 1), got {confidence}")


def _t_half_width(values: np.ndarray, confidence: float) -> float | None:
    """Half-width of the Student t-interval of the mean of ``values``; None for n = 1."""
    n = values.size
    if n < 2:
        return None
    sem = float(values.std(ddof=1)) / math.sqrt(n)
    return float(sps.t.ppf(0.5 + confidence / 2.0, n - 1)) * sem


def mean_ci(values: Sequence[float], confidence: float = 0.95) -> tuple[float, float | None]:
    """Mean of ``values`` and the half-width of its Student t-interval.

    Args:
        values: One value per seed.
        confidence: Confidence level of the interval.

    Returns:
        ``(mean, half_width)``; ``half_width`` is None with a single value.

    Raises:
        ValueError: Empty or non-finite values, or a confidence outside (0, 1).
    """
    _check_confidence(confidence)
    arr = _as_array(values, "values")
    return float(arr.mean()), _t_half_width(arr, confidence)


@dataclass(frozen=True)
class PairedDiff:
    """Paired comparison of ``other`` against ``baseline`` over the same seeds.

    Differences are ``baseline - other`` (``positive="lower"``, the default: lower TTD
    is better, so a positive difference means ``other`` is better), or ``other -
    baseline`` (``positive="higher"``: for a metric where more is better, or one with no
    better side); which one a metric takes is
    :func:`~rtaw_marl.evaluation.metric_goals.metric_difference`'s to say.

    Attributes:
        n: Number of paired seeds.
        confidence: Confidence level of the intervals.
        baseline_mean: Mean of the baseline's values.
        other_mean: Mean of the other policy's values.
        mean: Mean per-seed difference (``baseline - other``, or ``other - baseline``
            when made with ``positive="higher"``).
        sd: Sample standard deviation of the per-seed differences; None for n = 1.
        low: Lower end of the paired t-interval of ``mean``; None for n = 1.
        high: Upper end; None for n = 1.
        pct: ``mean`` in percent of ``baseline_mean``; None when that mean is 0.
        pct_low: ``low`` in percent of ``baseline_mean``; None when undefined.
        pct_high: ``high`` in percent of ``baseline_mean``; None when undefined.
        significant: The interval exists and excludes 0.
    """

    n: int
    confidence: float
    baseline_mean: float
    other_mean: float
    mean: float
    sd: float | None
    low: float | None
    high: float | None
    pct: float | None
    pct_low: float | None
    pct_high: float | None
    significant: bool

    def as_dict(self) -> dict[str, Any]:
        """A JSON-ready dict (intervals as ``[low, high]`` or ``None``, never NaN)."""
        ci = None if self.low is None or self.high is None else [self.low, self.high]
        pct_ci = (
            None if self.pct_low is None or self.pct_high is None else [self.pct_low, self.pct_high]
        )
        return {
            "method": METHOD,
            "n": self.n,
            "confidence": self.confidence,
            "baseline_mean": self.baseline_mean,
            "other_mean": self.other_mean,
            "mean_diff": self.mean,
            "sd_diff": self.sd,
            "ci": ci,
            "pct": self.pct,
            "pct_ci": pct_ci,
            "significant": self.significant,
        }


def paired_difference(
    baseline: Sequence[float],
    other: Sequence[float],
    confidence: float = 0.95,
    positive: Literal["lower", "higher"] = "lower",
) -> PairedDiff:
    """Paired Student t comparison of ``other`` against ``baseline`` (same seeds, same order).

    Args:
        baseline: The baseline's value per seed (e.g. MPDM's TTD).
        other: The other policy's value per seed, in the same seed order.
        confidence: Confidence level of the interval.
        positive: When the difference is positive: ``"lower"``, ``other`` below the
            baseline (``baseline - other``, for TTD); ``"higher"``, ``other`` above it
            (``other - baseline``, e.g. tasks finished).

    Returns:
        The mean difference ``baseline - other`` (positive: ``other`` is lower, i.e.
        better for TTD), or ``other - baseline`` with ``positive="higher"``, its
        interval, both also in percent of the baseline's mean, and whether the interval
        excludes 0.

    Raises:
        ValueError: Different lengths, empty or non-finite values, or a confidence
            outside (0, 1).
    """
    _check_confidence(confidence)
    base = _as_array(baseline, "baseline")
    oth = _as_array(other, "other")
    if base.size != oth.size:
        raise ValueError(f"paired samples differ in length: {base.size} vs {oth.size}")
    if positive not in ("lower", "higher"):
        raise ValueError(f"positive must be 'lower' or 'higher', got {positive!r}")
    diff = base - oth if positive == "lower" else oth - base
    n = int(diff.size)
    mean = float(diff.mean())
    half = _t_half_width(diff, confidence)
    sd = float(diff.std(ddof=1)) if n > 1 else None
    low = None if half is None else mean - half
    high = None if half is None else mean + half
    base_mean = float(base.mean())

    def pct(value: float | None) -> float | None:
        return None if value is None or base_mean == 0.0 else 100.0 * value / base_mean

    # A negative baseline mean would flip the percent bounds; order them again.
    pct_low, pct_high = pct(low), pct(high)
    if pct_low is not None and pct_high is not None and pct_low > pct_high:
        pct_low, pct_high = pct_high, pct_low
    return PairedDiff(
        n=n,
        confidence=confidence,
        baseline_mean=base_mean,
        other_mean=float(oth.mean()),
        mean=mean,
        sd=sd,
        low=low,
        high=high,
        pct=pct(mean),
        pct_low=pct_low,
        pct_high=pct_high,
        significant=low is not None and high is not None and (low > 0.0 or high < 0.0),
    )


@dataclass(frozen=True)
class HindsightShare:
    """Share of hindsight's gain over MPDM that a policy captures.

    Attributes:
        n: Number of paired seeds.
        confidence: Confidence level of the interval.
        share: ``(mean(mpdm) - mean(policy)) / (mean(mpdm) - mean(hindsight))``; 1 means
            the policy matches hindsight, 0 means it matches MPDM, negative is worse
            than MPDM.
        low: Lower end of the delta-method t-interval; None for n = 1.
        high: Upper end; None for n = 1.
    """

    n: int
    confidence: float
    share: float
    low: float | None
    high: float | None

    def as_dict(self) -> dict[str, Any]:
        """A JSON-ready dict (interval as ``[low, high]`` or ``None``, never NaN)."""
        ci = None if self.low is None or self.high is None else [self.low, self.high]
        return {
            "method": "delta-method t-interval of a ratio of paired means",
            "n": self.n,
            "confidence": self.confidence,
            "share": self.share,
            "ci": ci,
        }


def hindsight_share(
    mpdm: Sequence[float],
    policy: Sequence[float],
    hindsight: Sequence[float],
    confidence: float = 0.95,
) -> HindsightShare | None:
    """How much of hindsight's TTD gain over MPDM ``policy`` captures (same seeds).

    Args:
        mpdm: MPDM's TTD per seed.
        policy: The policy's TTD per seed.
        hindsight: The hindsight reference's TTD per seed.
        confidence: Confidence level of the interval.

    Returns:
        The share and its delta-method interval, or None when hindsight does not beat
        MPDM on average (the share is then meaningless).

    Raises:
        ValueError: Different lengths, empty or non-finite values, or a confidence
            outside (0, 1).
    """
    _check_confidence(confidence)
    base = _as_array(mpdm, "mpdm")
    pol = _as_array(policy, "policy")
    hind = _as_array(hindsight, "hindsight")
    if not base.size == pol.size == hind.size:
        raise ValueError(f"paired samples differ in length: {base.size}, {pol.size}, {hind.size}")
    gain = base - pol  # the policy's per-seed gain over MPDM
    reference = base - hind  # hindsight's per-seed gain over MPDM
    denominator = float(reference.mean())
    if denominator <= 0.0:
        return None
    share = float(gain.mean()) / denominator
    # Delta method: share - R = mean(gain - R * reference) / mean(reference); the
    # residuals' t-interval, divided by the denominator, is the share's interval.
    half = _t_half_width(gain - share * reference, confidence)
    if half is not None:
        half /= denominator
    return HindsightShare(
        n=int(base.size),
        confidence=confidence,
        share=share,
        low=None if half is None else share - half,
        high=None if half is None else share + half,
    )


def pooled_difference(
    pairs: Sequence[tuple[Sequence[float], Sequence[float]]], confidence: float = 0.95
) -> PairedDiff | None:
    """One comparison pooled over several settings (the rows of a table).

    Each setting's per-seed differences ``baseline - other`` are put in percent of that
    setting's baseline mean, so settings of different scales weigh alike; the result is
    the t-interval of the mean over all setting-seed pairs (its ``mean``, ``low`` and
    ``high`` are in percent; ``n`` counts the pairs).

    Args:
        pairs: ``(baseline, other)`` per setting, each one value per seed.
        confidence: Confidence level of the interval.

    Returns:
        The pooled difference, or None without any setting.
    """
    if not pairs:
        return None
    diffs = np.concatenate([100 * (np.asarray(b) - np.asarray(o)) / np.mean(b) for b, o in pairs])
    return paired_difference(diffs, np.zeros_like(diffs), confidence)


def pooled_hindsight_share(
    rows: Sequence[tuple[Sequence[float], Sequence[float], Sequence[float]]],
) -> float | None:
    """The hindsight share pooled over settings, as a ratio of means.

    The mean over settings of ``1 - mean(policy) / mean(mpdm)`` divided by the same for
    hindsight (not a mean of per-setting shares, which a setting where hindsight gains
    little would dominate).

    Args:
        rows: ``(mpdm, policy, hindsight)`` per setting, each one value per seed.

    Returns:
        The share, or None without any setting or when hindsight gains nothing.
    """
    if not rows:
        return None

    def gain(mpdm: Sequence[float], policy: Sequence[float]) -> float:
        return 1.0 - float(np.mean(policy) / np.mean(mpdm))

    reference = float(np.mean([gain(m, h) for m, _, h in rows]))
    if reference <= 0:
        return None
    return float(np.mean([gain(m, p) for m, p, _ in rows]) / reference)
