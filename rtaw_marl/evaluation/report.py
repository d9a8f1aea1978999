"""Results tables and atomic result files."""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from rtaw_marl.utils.atomic import atomic_write

__all__ = ["format_table", "improvement", "write_json_atomic"]


def improvement(baseline: Sequence[float], other: Sequence[float]) -> float:
    """Percent by which the mean of ``other`` is below the mean of ``baseline``."""
    base = float(np.mean(baseline))
    return 100.0 * (base - float(np.mean(other))) / base if base else 0.0


def _mean_std(values: Sequence[float]) -> str:
    arr = np.asarray(values, dtype=np.float64)
    return f"{arr.mean():.2f} ± {arr.std():.2f}"


def format_table(
    results: Mapping[str, Mapping[str, Sequence[float]]], reference: str = "mpdm"
) -> str:
    """A markdown table: mean ± std over seeds of TTD and makespan per policy.

    Args:
        results: ``{policy: {metric: [per seed]}}`` as returned by ``evaluate``.
        reference: Policy the improvement column is measured against; the column is
            left out when that policy was not evaluated.

    Returns:
        The table as a string.
    """
    with_ref = reference in results
    header = ["policy", "TTD", "makespan", "max wait", "s/episode"]
    if with_ref:
        header.append(f"TTD vs {reference.upper()}")
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
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
        lines.append("| " + " | ".join(row) + " |")
    return "\n".join(lines)


def write_json_atomic(path: str | Path, payload: Any) -> Path:
    """Write ``payload`` as indented JSON, atomically (temporary file + rename)."""
    data = json.dumps(payload, indent=2).encode()
    return atomic_write(path, lambda fh: fh.write(data))
