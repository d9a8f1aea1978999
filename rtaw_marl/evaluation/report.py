"""Results tables, paired comparisons for ``results.json``, and atomic result files."""

from __future__ import annotations

import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from rtaw_marl.evaluation.metric_goals import difference_wording, metric_difference
from rtaw_marl.evaluation.stats import (
    HindsightShare,
    PairedDiff,
    hindsight_share,
    mean_ci,
)
from rtaw_marl.utils.atomic import atomic_write

__all__ = [
    "HINDSIGHT",
    "baseline_label",
    "comparisons",
    "diff_cell",
    "format_table",
    "gap_to_bound",
    "improvement",
    "json_safe",
    "legend",
    "markdown_table",
    "mean_ci_cell",
    "write_json_atomic",
]

#: Name of the policy that knows the future: the reference of the hindsight share.
HINDSIGHT = "hindsight"

Results = Mapping[str, Mapping[str, Sequence[float]]]


def improvement(baseline: Sequence[float], other: Sequence[float]) -> float:
    """Percent by which the mean of ``other`` is below the mean of ``baseline``."""
    base = float(np.mean(baseline))
    return 100.0 * (base - float(np.mean(other))) / base if base else 0.0


def gap_to_bound(ttd: Sequence[float], bound: Sequence[float]) -> list[float]:
    """Per-seed percent by which each TTD exceeds the lower bound."""
    return [100.0 * (t - b) / b if b else 0.0 for t, b in zip(ttd, bound, strict=True)]


@dataclass
class _Comparison:
    """One policy's comparisons: paired differences by baseline, and its hindsight share."""

    vs: dict[str, PairedDiff] = field(default_factory=dict)
    share: HindsightShare | None = None
    has_share: bool = False


def _baselines(results: Results, reference: str, compare_to: str | None) -> list[str]:
    """The evaluated baselines every policy is compared against, without repeats."""
    names = [reference] if compare_to is None else [reference, compare_to]
    return [n for i, n in enumerate(names) if n in results and n not in names[:i]]


def _compare(
    results: Results,
    reference: str,
    compare_to: str | None,
    hindsight: str,
    confidence: float,
) -> dict[str, _Comparison]:
    baselines = _baselines(results, reference, compare_to)
    with_share = hindsight in results and reference in results
    out: dict[str, _Comparison] = {}
    for name, metrics in results.items():
        entry = _Comparison(has_share=with_share)
        for base in baselines:
            if base != name:
                entry.vs[base] = metric_difference(
                    "ttd", results[base]["ttd"], metrics["ttd"], confidence
                )
        if with_share:
            entry.share = hindsight_share(
                results[reference]["ttd"], metrics["ttd"], results[hindsight]["ttd"], confidence
            )
        out[name] = entry
    return out


def comparisons(
    results: Results,
    reference: str = "mpdm",
    compare_to: str | None = None,
    hindsight: str = HINDSIGHT,
    confidence: float = 0.95,
) -> dict[str, dict[str, Any]]:
    """Paired TTD comparisons of every policy, as plain JSON-ready dicts.

    Args:
        results: ``{policy: {metric: [per seed]}}`` as returned by ``evaluate``.
        reference: The main baseline (MPDM); skipped when it was not evaluated.
        compare_to: A second baseline, skipped when None or not evaluated.
        hindsight: The policy that knows the future; the share of its gain over
            ``reference`` is reported when both were evaluated.
        confidence: Confidence level of the intervals.

    Returns:
        ``{policy: {"vs": {baseline: PairedDiff.as_dict()}, "hindsight_share":
        HindsightShare.as_dict() or None}}``; a policy is not compared with itself, and
        ``hindsight_share`` is there only when hindsight and the reference were evaluated
        (None when hindsight does not beat the reference on average).
    """
    out: dict[str, dict[str, Any]] = {}
    for name, entry in _compare(results, reference, compare_to, hindsight, confidence).items():
        item: dict[str, Any] = {"vs": {base: diff.as_dict() for base, diff in entry.vs.items()}}
        if entry.has_share:
            item["hindsight_share"] = None if entry.share is None else entry.share.as_dict()
        out[name] = item
    return out


def baseline_label(name: str) -> str:
    """A baseline's name in a column header: MPDM, RBTS; other names as they are."""
    return name.upper() if name.isalpha() else name


def mean_ci_cell(values: Sequence[float], confidence: float) -> str:
    """``12.34 ± 0.56``: the mean and the half-width of its t-interval (the mean alone
    for one value)."""
    mean, half = mean_ci(values, confidence)
    return f"{mean:.2f}" if half is None else f"{mean:.2f} ± {half:.2f}"


def diff_cell(diff: PairedDiff) -> str:
    """``+3.1% [+1.2, +5.0]*``: a paired difference in percent of the baseline, its
    interval, ``*`` where the interval excludes 0."""
    if diff.pct is None:
        return "n/a"
    if diff.pct_low is None or diff.pct_high is None:
        return f"{diff.pct:+.1f}% [n/a]"
    star = "*" if diff.significant else ""
    return f"{diff.pct:+.1f}% [{diff.pct_low:+.1f}, {diff.pct_high:+.1f}]{star}"


def _share_cell(share: HindsightShare | None) -> str:
    if share is None:
        return "n/a"
    if share.low is None or share.high is None:
        return f"{100 * share.share:.0f}%"
    return f"{100 * share.share:.0f}% [{100 * share.low:.0f}, {100 * share.high:.0f}]"


def legend(
    n: int,
    confidence: float,
    baselines: list[str],
    with_share: bool,
    reference: str,
    metric: str = "ttd",
) -> str:
    """The one-line legend under a table of ``n`` seeds compared with ``baselines`` on
    ``metric`` (the sign's wording: :func:`~rtaw_marl.evaluation.metric_goals.
    difference_wording`)."""
    level = f"{100 * confidence:g}%"
    if n < 2:
        parts = ["1 seed: no intervals (run 2+ seeds)"]
    else:
        parts = [f"± and [low, high]: {level} Student t-intervals over {n} seeds"]
    if baselines:
        side, sign = difference_wording(metric)
        parts.append(f"vs X: {side} X's, paired per seed, in % of X's mean ({sign})")
        if n >= 2:
            parts.append("* = interval excludes 0")
    if with_share:
        parts.append(
            "hindsight share: part of hindsight's TTD gain over "
            f"{baseline_label(reference)} reached"
        )
    return "; ".join(parts)


def format_table(
    results: Results,
    reference: str = "mpdm",
    lower_bound: Sequence[float] | None = None,
    compare_to: str | None = None,
    hindsight: str = HINDSIGHT,
    confidence: float = 0.95,
) -> str:
    """A markdown table of the policies' metrics and paired comparisons, and a legend.

    Per policy: mean ± t-interval half-width over seeds of TTD, makespan and maximum
    wait, seconds per episode, then the paired TTD difference against ``reference``
    and ``compare_to`` in percent of the baseline's mean, with its interval and a
    ``*`` when the interval excludes 0 (:func:`~rtaw_marl.evaluation.stats.
    paired_difference`).

    Args:
        results: ``{policy: {metric: [per seed]}}`` as returned by ``evaluate``.
        reference: The main baseline (MPDM); its column is left out when it was not
            evaluated.
        lower_bound: Per-seed TTD lower bounds; adds a bound row and a gap column.
        compare_to: A second baseline; adds a column when it was evaluated.
        hindsight: The policy that knows the future; when it and ``reference`` were
            evaluated, its row is labelled as a reference and a column gives every
            policy's share of its gain over ``reference``.
        confidence: Confidence level of the intervals.

    Returns:
        The table and a one-line legend below it, as a string.
    """
    baselines = _baselines(results, reference, compare_to)
    compared = _compare(results, reference, compare_to, hindsight, confidence)
    with_share = hindsight in results and reference in results
    level = f"{100 * confidence:g}% CI"
    header = [
        "policy",
        f"TTD ± {level}",
        f"makespan ± {level}",
        f"max wait ± {level}",
        "s/episode",
    ]
    header += [f"TTD vs {baseline_label(base)}" for base in baselines]
    if with_share:
        header.append("hindsight share")
    if lower_bound is not None:
        header.append("gap to bound")
    rows = []
    if lower_bound is not None:
        bound_row = ["lower bound", mean_ci_cell(lower_bound, confidence)]
        rows.append(bound_row + [""] * (len(header) - len(bound_row)))
    for name, metrics in results.items():
        label = (
            f"{name} (reference: knows the future)" if with_share and name == hindsight else name
        )
        row = [
            label,
            mean_ci_cell(metrics["ttd"], confidence),
            mean_ci_cell(metrics["makespan"], confidence),
            mean_ci_cell(metrics["wait_max"], confidence),
            f"{np.mean(metrics['wall_time_s']):.3f}",
        ]
        entry = compared[name]
        row += [diff_cell(entry.vs[base]) if base in entry.vs else "—" for base in baselines]
        if with_share:
            # The share is 0 and 1 by definition on the two references' own rows.
            row.append("—" if name in (reference, hindsight) else _share_cell(entry.share))
        if lower_bound is not None:
            row.append(f"{np.mean(gap_to_bound(metrics['ttd'], lower_bound)):.1f}%")
        rows.append(row)
    n = min((len(m["ttd"]) for m in results.values()), default=0)
    note = legend(n, confidence, baselines, with_share, reference)
    return markdown_table(header, rows) + "\n" + note


def markdown_table(head: Sequence[str], rows: Sequence[Sequence[str]]) -> str:
    """A markdown table: a header line, its rule, one line per row."""
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    return "\n".join([*lines, *("| " + " | ".join(r) + " |" for r in rows)])


def json_safe(value: Any) -> Any:
    """``value`` with every NaN or infinite float replaced by None, numpy scalars and
    arrays made plain, tuples made lists: strict JSON has no NaN or Infinity."""
    if isinstance(value, Mapping):
        return {str(k): json_safe(v) for k, v in value.items()}
    if isinstance(value, (list, tuple, np.ndarray)):
        return [json_safe(v) for v in value]
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def write_json_atomic(path: str | Path, payload: Any) -> Path:
    """Write ``payload`` as indented, strict JSON, atomically (temporary file + rename).

    Non-finite floats become ``null`` (:func:`json_safe`), so every JSON parser reads it.
    """
    data = json.dumps(json_safe(payload), indent=2, allow_nan=False).encode()
    return atomic_write(path, lambda fh: fh.write(data))
