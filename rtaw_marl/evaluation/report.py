"""Results tables and atomic result files."""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from rtaw_marl.utils.atomic import atomic_write

__all__ = ["format_table", "gap_to_bound", "improvement", "write_json_atomic"]


def improvement(baseline: Sequence[float], other: Sequence[float]) -> float:
    """Percent by which the mean of ``other`` is below the mean of ``baseline``."""
    base = float(np.mean(baseline))
    return 100.0 * (base - float(np.mean(other))) / base if base else 0.0


def _mean_std(values: Sequence[float]) -> str:
    arr = np.asarray(values, dtype=np.float64)
    return f"{arr.mean():.2f} ± {arr.std():.2f}"


def gap_to_bound(ttd: Sequence[float], bound: Sequence[float]) -> list[float]:
    """Per-seed percent by which each TTD exceeds the lower bound."""
    return [100.0 * (t - b) / b if b else 0.0 for t, b in zip(ttd, bound, strict=True)]


def format_table(
    results: Mapping[str, Mapping[str, Sequence[float]]],
    reference: str = "mpdm",
    lower_bound: Sequence[float] | None = None,
) -> str:
    """A markdown table: mean ± std over seeds of TTD and makespan per policy.

    Args:
        results: ``{policy: {metric: [per seed]}}`` as returned by ``evaluate``.
        reference: Policy the improvement column is measured against; the column is
            left out when that policy was not evaluated.
        lower_bound: Per-seed TTD lower bounds; adds a bound row and a gap column.

    Returns:
        The table as a string.
    """
    with_ref = reference in results
    header = ["policy", "TTD", "makespan", "max wait", "s/episode"]
    if with_ref:
        header.append(f"TTD vs {reference.upper()}")
    if lower_bound is not None:
        header.append("gap to bound")
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    if lower_bound is not None:
        bound_row = ["lower bound", _mean_std(lower_bound), "", "", ""]
        bound_row += [""] * (len(header) - len(bound_row))
        lines.append("| " + " | ".join(bound_row) + " |")
    for name, metrics in results.items():
        row = [
            name,
            _mean_std(metrics["ttd"]),
            _mean_std(metrics["makespan"]),
            _mean_std(metrics["wait_max"]),
            f"{np.mean(metrics['wall_time_s']):.3f}",
        ]
        if with_ref:
            row.append(f"{improvement(results[reference]['ttd'], metrics['ttd']):+.1f}%")
        if lower_bound is not None:
            row.append(f"{np.mean(gap_to_bound(metrics['ttd'], lower_bound)):.1f}%")
        lines.append("| " + " | ".join(row) + " |")
    return "\n".join(lines)


def write_json_atomic(path: str | Path, payload: Any) -> Path:
    """Write ``payload`` as indented JSON, atomically (temporary file + rename)."""
    data = json.dumps(payload, indent=2).encode()
    return atomic_write(path, lambda fh: fh.write(data))
