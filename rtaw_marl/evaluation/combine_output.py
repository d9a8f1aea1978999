"""The combined table of a sweep (:mod:`rtaw_marl.evaluation.combine`) as markdown, CSV,
JSON and a PNG plot, each written atomically."""

from __future__ import annotations

import csv
import io
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from rtaw_marl.evaluation.combine import Combined, Row
from rtaw_marl.evaluation.report import (
    baseline_label,
    diff_cell,
    legend,
    markdown_table,
    mean_ci_cell,
    write_json_atomic,
)
from rtaw_marl.evaluation.stats import mean_ci
from rtaw_marl.utils.atomic import atomic_write

__all__ = ["OUTPUT_STEM", "combined_payload", "combined_table", "write_combined"]

#: The combined files are ``<folder>/combined.{txt,csv,json,png}``.
OUTPUT_STEM = "combined"


def combined_table(combined: Combined, confidence: float = 0.95) -> str:
    """A markdown table, one row per policy and setting, and ``rtaw-eval``'s legend.

    Columns: the swept keys, the policy, the number of seeds, mean TTD ± the
    half-width of its t-interval, then the paired TTD difference with each baseline
    (``+`` = below the baseline's TTD) as ``rtaw-eval`` prints it.
    """
    level = f"{100 * confidence:g}% CI"
    head = [*combined.swept, "policy", "seeds", f"TTD ± {level}"]
    head += [f"TTD vs {baseline_label(base)}" for base in combined.baselines]
    rows = []
    for row in combined.rows:
        cells = [*row.setting.values(), row.policy, str(len(row.seeds))]
        cells.append(mean_ci_cell(row.ttd, confidence))
        cells += [diff_cell(row.vs[b]) if b in row.vs else "—" for b in combined.baselines]
        rows.append(cells)
    n = min(len(row.seeds) for row in combined.rows)
    note = legend(n, confidence, combined.baselines, False, "")
    return markdown_table(head, rows) + "\n" + note


def _interval(values: Sequence[float], confidence: float) -> tuple[float, list[float] | None]:
    mean, half = mean_ci(values, confidence)
    return mean, None if half is None else [mean - half, mean + half]


def combined_payload(combined: Combined, confidence: float = 0.95) -> dict[str, Any]:
    """The combined rows as a JSON-ready dict: per row its setting, policy, seeds,
    per-seed TTD, mean, interval and comparisons (``PairedDiff.as_dict()``)."""
    rows = []
    for row in combined.rows:
        mean, ci = _interval(row.ttd, confidence)
        rows.append(
            {
                "setting": row.setting,
                "policy": row.policy,
                "seeds": row.seeds,
                "ttd": row.ttd,
                "ttd_mean": mean,
                "ttd_ci": ci,
                "vs": {base: diff.as_dict() for base, diff in row.vs.items()},
                "source": row.source,
            }
        )
    return {
        "swept": combined.swept,
        "baselines": combined.baselines,
        "confidence": confidence,
        "sources": combined.sources,
        "rows": rows,
    }


def _csv_text(combined: Combined, confidence: float) -> str:
    """One line per row; a comparison's columns are empty where it does not exist."""
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    head = [*combined.swept, "policy", "seeds", "ttd_mean", "ttd_ci_low", "ttd_ci_high"]
    for base in combined.baselines:
        head += [f"vs_{base}_pct", f"vs_{base}_pct_low", f"vs_{base}_pct_high"]
        head.append(f"vs_{base}_significant")
    writer.writerow([*head, "source"])
    for row in combined.rows:
        mean, ci = _interval(row.ttd, confidence)
        line: list[Any] = [*row.setting.values(), row.policy, len(row.seeds), mean]
        line += ci or ["", ""]
        for base in combined.baselines:
            diff = row.vs.get(base)
            if diff is None:
                line += ["", "", "", ""]
            else:
                line += [diff.pct, diff.pct_low, diff.pct_high, diff.significant]
        writer.writerow(["" if v is None else v for v in [*line, row.source]])
    return out.getvalue()


def _setting_label(row: Row) -> str:
    return "\n".join(f"{k}={v}" for k, v in row.setting.items()) or "all"


def _plot(path: Path, combined: Combined, confidence: float) -> Path:
    """Grouped bars: mean TTD per setting and policy with its interval; beside it, the
    paired difference with the first baseline (when one was evaluated)."""
    from matplotlib.figure import Figure  # the cli extra; no pyplot state

    settings = list(dict.fromkeys(_setting_label(row) for row in combined.rows))
    policies = list(dict.fromkeys(row.policy for row in combined.rows))
    base = combined.baselines[0] if combined.baselines else None
    panels = 2 if base is not None else 1
    width = max(6.0, 1.2 * len(settings) * panels + 2)
    fig = Figure(figsize=(width, 4.5), layout="constrained")
    axes = fig.subplots(1, panels, squeeze=False)[0]
    x = np.arange(len(settings))
    step = 0.8 / len(policies)
    for i, policy in enumerate(policies):
        mine = {_setting_label(r): r for r in combined.rows if r.policy == policy}
        at = [j for j, s in enumerate(settings) if s in mine]
        rows = [mine[settings[j]] for j in at]
        means = [mean_ci(r.ttd, confidence) for r in rows]
        offset = x[at] - 0.4 + step * (i + 0.5)
        # One colour per policy in both panels (the baseline has no bar in the second).
        axes[0].bar(offset, [m for m, _ in means], step, yerr=[h or 0.0 for _, h in means],
                    label=policy, capsize=2, color=f"C{i}")  # fmt: skip
        if base is None:
            continue
        vs = [(j, r.vs[base]) for j, r in zip(offset, rows, strict=True) if base in r.vs]
        vs = [(j, d) for j, d in vs if d.pct is not None]
        if vs:
            pct = np.array([d.pct for _, d in vs])
            low = np.array([d.pct if d.pct_low is None else d.pct_low for _, d in vs])
            high = np.array([d.pct if d.pct_high is None else d.pct_high for _, d in vs])
            axes[1].bar([j for j, _ in vs], pct, step, yerr=[pct - low, high - pct],
                        label=policy, capsize=2, color=f"C{i}")  # fmt: skip
    level = f"{100 * confidence:g}%"
    axes[0].set_ylabel(f"TTD (mean, {level} interval)")
    if base is not None:
        axes[1].axhline(0.0, color="black", linewidth=0.8)
        axes[1].set_ylabel(f"TTD vs {baseline_label(base)} (%, + = better, paired)")
    for ax in axes:
        ax.set_xticks(x, settings, fontsize=8)
    axes[0].legend(fontsize=8)
    return atomic_write(path, lambda fh: fig.savefig(fh, format="png", dpi=120))


def write_combined(
    folder: str | Path, combined: Combined, table: str, confidence: float = 0.95
) -> dict[str, Path]:
    """Write ``combined.txt`` (``table``), ``.csv``, ``.json`` and ``.png`` into
    ``folder``, each atomically; returns them by suffix."""
    folder = Path(folder)
    stem = folder / OUTPUT_STEM
    text, rows = f"{table}\n".encode(), _csv_text(combined, confidence).encode()
    return {
        "txt": atomic_write(stem.with_suffix(".txt"), lambda fh: fh.write(text)),
        "csv": atomic_write(stem.with_suffix(".csv"), lambda fh: fh.write(rows)),
        "json": write_json_atomic(
            stem.with_suffix(".json"), combined_payload(combined, confidence)
        ),
        "png": _plot(stem.with_suffix(".png"), combined, confidence),
    }
