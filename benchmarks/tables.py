"""Markdown cells and sections of the paper's tables, from per-seed TTDs.

A row is ``{label: [ttd per seed]}`` (one cell of a study). Every comparison is paired
per seed (:func:`~rtaw_marl.evaluation.stats.paired_difference`); pooled lines put each
row's per-seed differences in percent of that row's baseline mean
(:func:`~rtaw_marl.evaluation.stats.pooled_difference`); the pooled hindsight share is a
ratio of means (:func:`~rtaw_marl.evaluation.stats.pooled_hindsight_share`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from rtaw_marl.evaluation.report import diff_cell, markdown_table
from rtaw_marl.evaluation.stats import (
    PairedDiff,
    hindsight_share,
    paired_difference,
    pooled_difference,
    pooled_hindsight_share,
)
from rtaw_marl.scenarios import ROWS

__all__ = [
    "LEARNED",
    "ORDER",
    "RULES",
    "SHARES",
    "STRONGEST",
    "TABLE1",
    "TABLE2",
    "compare",
    "mean_cell",
    "percent",
    "pooled",
    "pooled_diff",
    "pooled_share",
    "section",
    "share",
    "share_line",
    "shares",
    "strongest_rule",
    "vs",
]

Row = Mapping[str, Sequence[float]]

#: Table I's scenarios in row order (10 robots, then 100, per layout).
TABLE1 = [
    ROWS[r] for r in ("direct", "direct_m100", *(x for p in "ABCDE" for x in (p, f"{p}_m100")))
]
#: Table II's scenarios in row order.
TABLE2 = [f"{grid}_m{m}_random" for m in (500, 1000) for grid in ("open300_direct", "C256_astar")]

#: Rule labels of the tables, then the learned ones, in column order.
RULE_LABELS = ("MPDM", "RBTS", "lookahead", "hungarian", "hindsight")
LEARNED = ("RTAW", "RTAW+")
ORDER = (*RULE_LABELS, *LEARNED)
#: Candidates for the strongest rule of a row.
RULES = ("RBTS", "lookahead", "hungarian")
#: Stands for the strongest rule of each row in a comparison.
STRONGEST = "the strongest rule"
#: Policies whose hindsight share the tables show.
SHARES = ("lookahead", *LEARNED)


def vs(base: Sequence[float], other: Sequence[float]) -> str:
    """``+3.1% [+1.2, +5.0]*``: ``other``'s TTD below ``base``'s, paired over seeds."""
    return diff_cell(paired_difference(base, other))


def share(row: Row, name: str) -> str:
    """``name``'s share of hindsight's gain over MPDM in this row, or ``-``."""
    if not {"MPDM", "hindsight", name} <= row.keys():
        return "-"
    s = hindsight_share(row["MPDM"], row[name], row["hindsight"])
    return "-" if s is None else f"{100 * s.share:.0f}%"


def shares(row: Row) -> str:
    return " / ".join(share(row, p) for p in SHARES)


def strongest_rule(row: Row) -> str:
    """The rule with the lowest mean TTD of the row."""
    candidates = (r for r in RULES if r in row)
    return min(candidates, key=lambda r: float(np.mean(row[r])), default="-")


def _baseline(row: Row, base: str) -> str:
    return strongest_rule(row) if base == STRONGEST else base


def compare(row: Row, base: str, other: str) -> str:
    """:func:`vs` of ``other`` against ``base`` (or :data:`STRONGEST`, then named), or ``-``."""
    rule = _baseline(row, base)
    if rule not in row or other not in row:
        return "-"
    cell = vs(row[rule], row[other])
    return f"{rule}: {cell}" if base == STRONGEST else cell


def pooled_diff(rows: Sequence[Row], base: str, other: str) -> PairedDiff | None:
    """``other`` against ``base`` pooled over the rows that have both."""
    pairs = [(t[b], t[other]) for t in rows if (b := _baseline(t, base)) in t and other in t]
    return pooled_difference(pairs)


def pooled(rows: Sequence[Row], base: str, other: str) -> str:
    """``+3.6% [+3.0, +4.3]* (n=240)`` or ``-``."""
    d = pooled_diff(rows, base, other)
    if d is None:
        return "-"
    mark = "*" if d.significant else ""
    ci = "" if d.low is None else f" [{d.low:+.1f}, {d.high:+.1f}]{mark}"
    return f"{d.mean:+.1f}%{ci} (n={d.n})"


def pooled_share(rows: Sequence[Row], name: str) -> float | None:
    """``name``'s hindsight share pooled over the rows that have it."""
    triples = [
        (t["MPDM"], t[name], t["hindsight"])
        for t in rows
        if {"MPDM", "hindsight", name} <= t.keys()
    ]
    return pooled_hindsight_share(triples)


def percent(value: float | None) -> str:
    return "-" if value is None else f"{100 * value:.0f}%"


def mean_cell(row: Row, name: str) -> str:
    return f"{np.mean(row[name]):.0f}" if name in row else "-"


def share_line(rows: Sequence[Row]) -> str:
    values = " / ".join(percent(pooled_share(rows, p)) for p in SHARES)
    return f"- hindsight share, pooled ({' / '.join(SHARES)}): {values}"


def wins(rows: Sequence[Row], base: str, other: str = "RTAW+") -> str:
    """How many rows ``other`` beats ``base`` on, significantly or not."""
    diffs = [paired_difference(t[base], t[other]) for t in rows if base in t and other in t]
    better = sum(d.mean > 0 for d in diffs)
    sig = sum(d.mean > 0 and d.significant for d in diffs)
    worse = sum(d.mean < 0 and d.significant for d in diffs)
    return (
        f"- {other} beats {base} on {better} of {len(diffs)} rows (significantly on "
        f"{sig}; significantly worse on {worse})"
    )


#: The paired comparisons of each row, (policy, baseline).
COMPARISONS = [("RTAW+", "MPDM"), ("RTAW+", "RBTS"), ("RTAW+", "hungarian"),
               ("RTAW+", "lookahead"), ("RTAW", "MPDM"), ("RTAW", STRONGEST)]  # fmt: skip
#: The pooled lines of a section, (policy, baseline).
POOLED = [*COMPARISONS[:4], ("RTAW+", STRONGEST), *COMPARISONS[4:], ("lookahead", "MPDM")]


def section(rows: Mapping[str, Row]) -> str:
    """Mean TTDs and hindsight shares, paired comparisons, then the pooled lines."""
    means = markdown_table(
        ["setting", *ORDER, "hindsight share: " + " / ".join(SHARES)],
        [[k, *(mean_cell(t, p) for p in ORDER), shares(t)] for k, t in rows.items()],
    )
    comparisons = markdown_table(
        ["setting", *(f"{o} vs {b}" for o, b in COMPARISONS)],
        [[k, *(compare(t, b, o) for o, b in COMPARISONS)] for k, t in rows.items()],
    )
    return f"{means}\n\n{comparisons}\n\n" + "\n".join(summary(list(rows.values())))


def summary(rows: Sequence[Row]) -> list[str]:
    """Pooled comparisons and shares, RTAW+'s wins per row and its goals."""
    lines = [f"- {o} vs {b}, pooled: {pooled(rows, b, o)}" for o, b in POOLED]
    lines.append(share_line(rows))
    lines += [wins(rows, b) for b in ("lookahead", "MPDM", "RBTS")]
    d, s = pooled_diff(rows, "MPDM", "RTAW+"), pooled_share(rows, "RTAW+")
    gain = "-" if d is None else f"{'met' if d.mean >= 10 else 'not met'} ({d.mean:+.1f}%)"
    part = "-" if s is None else f"{'met' if s >= 0.7 else 'not met'} ({percent(s)})"
    lines.append(
        f"- RTAW+ goals (reported, not asserted): >= +10% vs MPDM pooled: {gain}; "
        f">= 70% hindsight share pooled: {part}"
    )
    return lines
