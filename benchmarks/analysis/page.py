"""The generated part of docs/analysis.md: the two tables and the findings.

The findings are templated from the measured numbers: one bullet per topic, a clause
per policy, the lead words chosen by comparing the numbers (given in brackets).
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence

from benchmarks.analysis.decisions import LOOKAHEAD
from benchmarks.analysis.summary import Summary
from benchmarks.tables import percent
from rtaw_marl.evaluation.report import markdown_table
from rtaw_marl.sim.inputs import seed_span as _span

__all__ = ["choices_table", "findings", "section", "situations_table"]

#: Fewer deviations than this: a finding about them says the sample is small.
MIN_SAMPLE = 30

Pair = tuple[Summary, Summary]  # a learned policy's summary and lookahead's, same row


def cells(value: float | None) -> str:
    """``3.2`` (``-`` for None)."""
    return "-" if value is None else f"{value:.1f}"


def vs_mpdm(s: Summary) -> str:
    """Mean TTD and its change against MPDM's on the same seeds (negative: less TTD)."""
    return f"{s.ttd:.0f} ({100 * (s.ttd / s.mpdm_ttd - 1):+.1f}%)"


def choices_table(summaries: Sequence[Summary]) -> str:
    """Per policy and row: TTD, agreement with MPDM and lookahead, extra distance."""
    head = ["row", "policy", "decisions", "mean TTD (vs MPDM)", "picks nearest",
            "extra cells when not (mean / median)", "picks lookahead's",
            "when lookahead leaves nearest: same / nearest (n)"]  # fmt: skip
    rows = []
    for s in summaries:
        own = s.name == LOOKAHEAD
        la = "(itself)" if own else percent(s.lookahead)
        when = "(itself)" if own else (f"{percent(s.agree_if_lookahead_deviates)} / "
                                       f"{percent(s.nearest_if_lookahead_deviates)} "
                                       f"({s.lookahead_deviations})")  # fmt: skip
        rows.append([s.row, s.policy, str(s.decisions), vs_mpdm(s), percent(s.nearest),
                     f"{cells(s.extra_mean)} / {cells(s.extra_median)}", la, when])  # fmt: skip
    return markdown_table(head, rows)


def situations_table(summaries: Sequence[Summary]) -> str:
    """Per policy and row: in which situations it leaves the nearest task."""
    head = ["row", "policy", "deviations", "nearest contested: in deviations / in all",
            "deviation rate: nearest contested / not", "chosen uncontested",
            "chosen has shorter chain"]  # fmt: skip
    rows = [[s.row, s.policy, str(s.deviations),
             f"{percent(s.contested_in_deviations)} / {percent(s.contested_overall)}",
             f"{percent(s.deviate_if_contested)} / {percent(s.deviate_if_uncontested)}",
             percent(s.chosen_free), percent(s.shorter_chain)] for s in summaries]  # fmt: skip
    return markdown_table(head, rows)


# --------------------------------------------------------------------------- findings
def by_policy(summaries: Sequence[Summary]) -> dict[str, list[Pair]]:
    """Learned policy name -> (its summary, lookahead's) on each row it ran on."""
    reference = {s.row: s for s in summaries if s.name == LOOKAHEAD}
    out: dict[str, list[Pair]] = {}
    for s in summaries:
        if s.name != LOOKAHEAD:
            out.setdefault(s.name, []).append((s, reference[s.row]))
    return out


def verdict(pairs: Iterable[tuple[float | None, float | None]], more: str, less: str) -> str:
    """``more`` when the first value exceeds the second in every pair with both, ``less``
    when it is below in every one, else ``more`` qualified as holding on some rows only."""
    both = [(a, b) for a, b in pairs if a is not None and b is not None]
    if both and all(a > b for a, b in both):
        return more
    if both and all(a < b for a, b in both):
        return less
    return f"{more} on some rows only" if both else f"{more}: not measurable"


def _few(s: Summary) -> str:
    return f", only {s.deviations} deviations" if s.deviations < MIN_SAMPLE else ""


def nearest_clause(name: str, pairs: list[Pair]) -> str:
    lead = verdict(((s.nearest, la.nearest) for s, la in pairs),
                   "keeps the nearest task more often than lookahead",
                   "leaves the nearest task more often than lookahead")  # fmt: skip
    nums = "; ".join(f"{s.short}: {percent(s.nearest)} vs {percent(la.nearest)}"
                     for s, la in pairs)  # fmt: skip
    return f"`{name}` {lead} ({nums})"


def extra_clause(name: str, pairs: list[Pair]) -> str:
    lead = verdict(((s.extra_mean, la.extra_mean) for s, la in pairs),
                   "accepts more extra distance than lookahead",
                   "accepts less extra distance than lookahead")  # fmt: skip
    nums = "; ".join(f"{s.short}: mean {cells(s.extra_mean)} vs {cells(la.extra_mean)}, "
                     f"median {cells(s.extra_median)} vs {cells(la.extra_median)}{_few(s)}"
                     for s, la in pairs)  # fmt: skip
    return f"`{name}` {lead} ({nums})"


def contested_clause(name: str, rows: list[Summary]) -> str:
    lead = verdict(((s.deviate_if_contested, s.deviate_if_uncontested) for s in rows),
                   "leaves the nearest task more often when a rival reaches it first",
                   "leaves the nearest task less often when a rival reaches it first")  # fmt: skip
    nums = "; ".join(f"{s.short}: {percent(s.deviate_if_contested)} vs "
                     f"{percent(s.deviate_if_uncontested)} otherwise" for s in rows)  # fmt: skip
    return f"`{name}` {lead} ({nums})"


def target_clause(name: str, pairs: list[Pair]) -> str:
    free = verdict(((s.chosen_free, la.chosen_free) for s, la in pairs),
                   "more often uncontested", "less often uncontested")  # fmt: skip
    chain = verdict(((s.shorter_chain, la.shorter_chain) for s, la in pairs),
                    "more often has a shorter chain", "less often has a shorter chain")  # fmt: skip
    nums = "; ".join(f"{s.short}: uncontested {percent(s.chosen_free)} vs "
                     f"{percent(la.chosen_free)}, shorter chain {percent(s.shorter_chain)} vs "
                     f"{percent(la.shorter_chain)}" for s, la in pairs)  # fmt: skip
    return f"The task `{name}` takes instead, against lookahead's: {free}; {chain} ({nums})"


def agree_clause(name: str, pairs: list[Pair]) -> str:
    rows = [s for s, _ in pairs]
    lead = verdict(((s.agree_if_lookahead_deviates, 0.5) for s in rows),
                   "mostly makes the same choice", "mostly does not follow it")  # fmt: skip
    nums = "; ".join(f"{s.short}: of {s.lookahead_deviations} such decisions, same choice "
                     f"{percent(s.agree_if_lookahead_deviates)}, nearest task "
                     f"{percent(s.nearest_if_lookahead_deviates)}" for s in rows)  # fmt: skip
    return f"`{name}` {lead} ({nums})"


def ttd_clause(name: str, pairs: list[Pair]) -> str:
    return f"`{name}`: " + "; ".join(
        f"{s.short}: {100 * (s.ttd / s.mpdm_ttd - 1):+.1f}% vs MPDM, "
        f"{100 * (s.ttd / la.ttd - 1):+.1f}% vs lookahead"
        for s, la in pairs
    )


#: The findings' topics in order, and the clause each learned policy gets (None: where
#: they leave the nearest task, a clause per learned policy and one for lookahead).
TOPICS = [
    ("Nearest task (share of decisions, policy vs lookahead)", nearest_clause),
    ("Extra distance when leaving it (cells, policy vs lookahead)", extra_clause),
    ("Where they leave it (deviation rate, nearest task contested vs not)", None),
    ("What they take instead (share of deviations, policy vs lookahead)", target_clause),
    ("When lookahead leaves the nearest task", agree_clause),
    ("Mean TTD on these seeds (means only; paired intervals in [results.md](results.md))",
     ttd_clause),
]  # fmt: skip


def findings(summaries: Sequence[Summary]) -> list[str]:
    """The findings' bullets, one per topic of :data:`TOPICS` that has a clause."""
    learned = by_policy(summaries)
    reference = [s for s in summaries if s.name == LOOKAHEAD]
    out = []
    for title, clause in TOPICS:
        if clause is None:
            parts = [contested_clause(n, [s for s, _ in p]) for n, p in learned.items()]
            parts.append(contested_clause(LOOKAHEAD, reference))
        else:
            parts = [clause(n, p) for n, p in learned.items()]
        if parts:
            out.append(f"- **{title}**: " + " ".join(f"{c}." for c in parts))
    return out


# --------------------------------------------------------------------------- section
def seed_span(seeds: Sequence[int]) -> str:
    """``seed 0``, ``seeds 0-19`` or ``seeds 3, 5, 8``."""
    return f"seed{'s' if len(seeds) > 1 else ''} {_span(seeds)}"


def section(
    summaries: Sequence[Summary],
    seeds: Sequence[int],
    horizon: int,
    command: str,
    skipped: Sequence[str] = (),
) -> str:
    """The generated part of the page: the setting line, the two tables, the findings.

    Args:
        summaries: Per row, each learned policy's summary, then lookahead's.
        seeds: The episode seeds.
        horizon: Lookahead's horizon ``H``.
        command: What made it.
        skipped: Policies that did not load (``RTAW on A* layout C``).
    """
    rows = ", ".join(dict.fromkeys(s.row for s in summaries))
    parts = [
        f"Rows: {rows}; {seed_span(seeds)}; `lookahead` with H = {horizon}. Made with:",
        f"```\n{command}\n```",
        "## Choices",
        choices_table(summaries),
        "## Situations of the deviations",
        situations_table(summaries),
        "## Findings",
        "\n".join(findings(summaries)),
    ]
    if skipped:
        parts.append("Not loaded (skipped): " + ", ".join(skipped) + ".")
    return "\n\n".join(parts)
