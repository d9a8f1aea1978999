"""The combined table of a sweep (:mod:`rtaw_marl.evaluation.combine`) as markdown, CSV,
JSON and a PNG plot, written as one set.

:func:`render_combined` renders the four files in memory; :meth:`CombinedFiles.write`
writes each to a temporary file beside its target and then renames all four in together
with SIGINT and SIGTERM deferred (``signals_held``), so a stop leaves either the
previous files or the complete new set, never a mix (a crash or a full disk at any
moment leaves no partial file).
"""

from __future__ import annotations

import csv
import io
import json
import os
import tempfile
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from rtaw_marl.evaluation.combine import Combined, Row
from rtaw_marl.evaluation.report import (
    baseline_label,
    diff_cell,
    json_safe,
    legend,
    markdown_table,
    mean_ci_cell,
)
from rtaw_marl.evaluation.stats import mean_ci
from rtaw_marl.utils.atomic import disk_full_guard
from rtaw_marl.utils.signals import signals_held

__all__ = [
    "OUTPUT_STEM",
    "OUTPUT_SUFFIXES",
    "CombinedFiles",
    "combined_paths",
    "combined_payload",
    "combined_table",
    "render_combined",
    "write_combined",
]

#: The combined files are ``<folder>/combined.{txt,csv,json,png}``.
OUTPUT_STEM = "combined"
#: Their suffixes, in the order they are listed.
OUTPUT_SUFFIXES = ("txt", "csv", "json", "png")


def combined_paths(folder: str | Path) -> dict[str, Path]:
    """The combined files of ``folder`` by suffix: ``<folder>/combined.<suffix>``."""
    return {suffix: Path(folder) / f"{OUTPUT_STEM}.{suffix}" for suffix in OUTPUT_SUFFIXES}


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


def _plot(combined: Combined, confidence: float) -> bytes:
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
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=120)
    return buffer.getvalue()


@dataclass
class CombinedFiles:
    """The combined files, rendered and not yet written (:func:`render_combined`).

    Attributes:
        paths: Each file's target by suffix (:func:`combined_paths`).
        contents: Each file's bytes by suffix.
        written: Whether :meth:`write` has renamed all of them in; set inside the block
            that defers SIGINT and SIGTERM, so a stop handled right after it sees it.
    """

    paths: dict[str, Path]
    contents: dict[str, bytes]
    written: bool = field(default=False)

    def write(self) -> dict[str, Path]:
        """Write every file to a temporary beside its target (fsynced), then rename all
        of them in with SIGINT and SIGTERM deferred (``signals_held``); returns
        the targets by suffix.

        Raises:
            DiskFullError: The disk filled up; no target was changed and no temporary
                file is left.
        """
        staged: dict[str, Path] = {}
        try:
            for suffix, data in self.contents.items():
                staged[suffix] = _temporary(self.paths[suffix], data)
            # A signal here is handled after the block: every file or none is new.
            with signals_held():
                for suffix, temporary in staged.items():
                    os.replace(temporary, self.paths[suffix])
                self.written = True
        finally:
            for temporary in staged.values():  # gone once renamed; else the stop's leftovers
                temporary.unlink(missing_ok=True)
        return dict(self.paths)


def render_combined(
    folder: str | Path, combined: Combined, table: str, confidence: float = 0.95
) -> CombinedFiles:
    """``combined.txt`` (``table``), ``.csv``, ``.json`` and ``.png`` for ``folder``,
    rendered in memory; nothing is written yet (:meth:`CombinedFiles.write`)."""
    payload = json_safe(combined_payload(combined, confidence))
    contents = {
        "txt": f"{table}\n".encode(),
        "csv": _csv_text(combined, confidence).encode(),
        "json": json.dumps(payload, indent=2, allow_nan=False).encode(),
        "png": _plot(combined, confidence),
    }
    return CombinedFiles(combined_paths(folder), contents)


def write_combined(
    folder: str | Path, combined: Combined, table: str, confidence: float = 0.95
) -> dict[str, Path]:
    """Render and write ``combined.txt`` (``table``), ``.csv``, ``.json`` and ``.png``
    into ``folder`` as one set (:meth:`CombinedFiles.write`); returns them by suffix."""
    return render_combined(folder, combined, table, confidence).write()


def _temporary(path: Path, data: bytes) -> Path:
    """``data`` in a new fsynced file beside ``path``, named as
    :func:`~rtaw_marl.utils.atomic.temp_name` says (``.combined.csv.XXXXXXXX.tmp``)."""
    kept = f"the previous {path.name} is kept" if path.exists() else f"no {path.name} was written"
    with disk_full_guard(path, kept):
        fd, name = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
        temporary = Path(name)
        try:
            with os.fdopen(fd, "wb") as fh:
                # mkstemp creates the file 0600; give it the usual permissions instead.
                umask = os.umask(0)
                os.umask(umask)
                os.fchmod(fh.fileno(), 0o666 & ~umask)
                fh.write(data)
                fh.flush()
                os.fsync(fh.fileno())
        except BaseException:
            temporary.unlink(missing_ok=True)
            raise
    return temporary
