"""Markdown cells and sections of the paper's tables, from per-seed TTDs.

A row is ``{label: [ttd per seed]}`` (one cell of a study). Every comparison is paired
per seed (:func:`~rtaw_marl.evaluation.stats.paired_difference`); pooled lines put each
row's per-seed differences in percent of that row's baseline mean
(:func:`~rtaw_marl.evaluation.stats.pooled_difference`); the pooled hindsight share is a
ratio of means (:func:`~rtaw_marl.evaluation.stats.pooled_hindsight_share`).
"""

from __future__ import annotations

import json
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path

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
    "BEST",
    "LEARNED",
    "ORDER",
    "SHARES",
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
    "stored_best",
    "vs",
    "with_best",
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
#: The column of each row's bar: the best rule of its setting, chosen on the selection
#: seeds 1000-1019 among MPDM, RBTS, lookahead, hungarian and batch, and played on the
#: evaluation seeds (:func:`stored_best`, :func:`with_best`).
BEST = "the best rule"
#: The stored per-seed results (``search_<part>.json`` hold each row's best rule).
DATA = Path(__file__).with_name("data")
#: The tables' labels of the rules' names.
RULE_LABEL = {"mpdm": "MPDM", "rbts": "RBTS"}
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


def stored_best(*parts: str, data: Path | None = None) -> dict[str, tuple[str, list[float]]]:
    """Row key -> (its best rule, that rule's TTDs on the evaluation seeds), as
    ``benchmarks/scripts/search_tables.py`` chose and played them (``search_<part>.json``
    in ``data``, default :data:`DATA`)."""
    data = DATA if data is None else data
    out = {}
    for part in parts:
        for key, row in json.loads((data / f"search_{part}.json").read_text())["rows"].items():
            name = row["best_rule"]["name"]
            out[key] = (RULE_LABEL.get(name, name), [float(v) for v in row["ttd"][name]])
    return out


def with_best(
    rows: Mapping[str, Row],
    best: Mapping[str, tuple[str, Sequence[float]]],
    key: Callable[[str], str] = str,
) -> tuple[dict[str, Row], dict[str, str]]:
    """``rows`` with their best rule's TTDs as column :data:`BEST`, and the rule's name
    per row; rows whose ``key(row key)`` has no stored choice are left without.

    Raises:
        ValueError: A row holds the chosen rule with other TTDs than the stored ones on
            the seeds both have (then they are not the same episodes).
    """
    out: dict[str, Row] = {}
    names: dict[str, str] = {}
    for k, row in rows.items():
        if key(k) not in best:
            out[k] = row
            continue
        name, ttd = best[key(k)]
        n = min(len(ttd), *(len(v) for v in row.values()))
        if name in row and [float(v) for v in row[name][:n]] != list(ttd[:n]):
            raise ValueError(f"{k}: the stored {name} TTDs differ from this row's")
        out[k] = {**{c: v[:n] for c, v in row.items()}, BEST: ttd[:n]}
        names[k] = name
    return out, names


def compare(row: Row, base: str, other: str) -> str:
    """:func:`vs` of ``other`` against ``base``, or ``-``."""
    if base not in row or other not in row:
        return "-"
    return vs(row[base], row[other])


def pooled_diff(rows: Sequence[Row], base: str, other: str) -> PairedDiff | None:
    """``other`` against ``base`` pooled over the rows that have both."""
    pairs = [(t[base], t[other]) for t in rows if base in t and other in t]
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
               ("RTAW+", "lookahead"), ("RTAW", "MPDM"), ("RTAW", BEST)]  # fmt: skip
#: The pooled lines of a section, (policy, baseline).
POOLED = [*COMPARISONS[:4], ("RTAW+", BEST), *COMPARISONS[4:], ("lookahead", "MPDM")]


def section(rows: Mapping[str, Row], best: Mapping[str, str] | None = None) -> str:
    """Mean TTDs and hindsight shares, paired comparisons, then the pooled lines;
    ``best`` names each row's best rule (:func:`with_best`). Rows without a stored best
    rule (none given) have no comparison with it."""
    means = markdown_table(
        ["setting", *ORDER, "hindsight share: " + " / ".join(SHARES)],
        [[k, *(mean_cell(t, p) for p in ORDER), shares(t)] for k, t in rows.items()],
    )
    pairs = COMPARISONS if best else [c for c in COMPARISONS if c[1] != BEST]
    named = ["best rule (seeds 1000-1019)"] if best else []
    comparisons = markdown_table(
        ["setting", *named, *(f"{o} vs {b}" for o, b in pairs)],
        [
            [k, *([best.get(k, "-")] if best else []), *(compare(t, b, o) for o, b in pairs)]
            for k, t in rows.items()
        ],
    )
    return f"{means}\n\n{comparisons}\n\n" + "\n".join(summary(list(rows.values()), bool(best)))


def summary(rows: Sequence[Row], best: bool = True) -> list[str]:
    """Pooled comparisons (with the best rule only if ``best``) and shares, RTAW+'s wins
    per row and its goals."""
    lines = [f"- {o} vs {b}, pooled: {pooled(rows, b, o)}" for o, b in POOLED if best or b != BEST]
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
