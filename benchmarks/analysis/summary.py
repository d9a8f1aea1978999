"""One policy's decisions on one row pooled into shares and distances (a :class:`Summary`)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, fields

import numpy as np

from benchmarks.analysis.decisions import Decision

__all__ = ["Summary", "share", "summarise"]

_FIELDS = tuple(f.name for f in fields(Decision))


@dataclass(frozen=True)
class Summary:
    """Statistics of one trajectory set (one policy on one row, all seeds pooled).

    Shares are fractions in ``[0, 1]``; ``None`` where their denominator is empty.
    ``name`` is the policy as asked for (``RTAW+``, an entry, a path, ``lookahead``),
    ``policy`` its label on this row; ``row`` is the row's label and ``short`` its short
    name in the findings.
    """

    row: str
    short: str
    name: str
    policy: str
    seeds: int
    decisions: int
    ttd: float
    mpdm_ttd: float
    nearest: float
    lookahead: float
    deviations: int
    extra_mean: float | None
    extra_median: float | None
    contested_in_deviations: float | None
    contested_overall: float | None
    deviate_if_contested: float | None
    deviate_if_uncontested: float | None
    chosen_free: float | None
    shorter_chain: float | None
    lookahead_deviations: int
    agree_if_lookahead_deviates: float | None
    nearest_if_lookahead_deviates: float | None


def share(flags: np.ndarray, where: np.ndarray | None = None) -> float | None:
    """Fraction of ``flags`` that hold (among ``where``); ``None`` when empty."""
    picked = flags if where is None else flags[where]
    return float(picked.mean()) if picked.size else None


def summarise(
    decisions: Sequence[Decision],
    ttds: Sequence[float],
    mpdm_ttd: float,
    *,
    row: str,
    short: str,
    name: str,
    policy: str,
) -> Summary:
    """Pool one policy's decisions on one row into a :class:`Summary`.

    Args:
        decisions: Its decisions over every seed.
        ttds: Its TTD per seed.
        mpdm_ttd: MPDM's mean TTD on the same seeds.
        row: The row's label.
        short: The row's short name.
        name: The policy as asked for.
        policy: Its label on this row.
    """
    field = {f: np.array([getattr(d, f) for d in decisions]) for f in _FIELDS}
    dev = ~field["nearest"]
    contested = field["contested"]
    la_dev = ~field["lookahead_nearest"]
    extra = field["extra"][dev]
    return Summary(
        row=row, short=short, name=name, policy=policy,
        seeds=len(ttds), decisions=len(decisions),
        ttd=float(np.mean(ttds)), mpdm_ttd=mpdm_ttd,
        nearest=float(field["nearest"].mean()), lookahead=float(field["lookahead"].mean()),
        deviations=int(dev.sum()),
        extra_mean=float(extra.mean()) if extra.size else None,
        extra_median=float(np.median(extra)) if extra.size else None,
        contested_in_deviations=share(contested, dev), contested_overall=share(contested),
        deviate_if_contested=share(dev, contested), deviate_if_uncontested=share(dev, ~contested),
        chosen_free=share(field["chosen_free"], dev),
        shorter_chain=share(field["shorter_chain"], dev),
        lookahead_deviations=int(la_dev.sum()),
        agree_if_lookahead_deviates=share(field["lookahead"], la_dev),
        nearest_if_lookahead_deviates=share(field["nearest"], la_dev),
    )  # fmt: skip
