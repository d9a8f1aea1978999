"""The combined table of a sweep (:mod:`rtaw_marl.evaluation.combine`) as markdown, CSV,
JSON, a PNG plot (:mod:`~rtaw_marl.evaluation.combine_plot`) and the per-episode table,
written as one set.

:func:`render_combined` renders the five files in memory; :meth:`CombinedFiles.write`
writes each to a temporary file beside its target and then renames all five in together
with SIGINT and SIGTERM deferred (``signals_held``), so a stop leaves either the
previous files or the complete new set, never a mix (a crash or a full disk at any
moment leaves no partial file).

The table, CSV, JSON and plot are of one metric (:attr:`~rtaw_marl.evaluation.combine.
Combined.metric`, TTD by default): its columns and keys are named after it (``ttd_mean``,
``makespan_mean``). ``combined_episodes.csv`` holds every metric: one row per job,
policy and seed, the swept keys as columns.
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

from rtaw_marl.evaluation.combine import Combined
from rtaw_marl.evaluation.combine_plot import plot_png
from rtaw_marl.evaluation.metric_goals import metric_goal, metric_label
from rtaw_marl.evaluation.report import (
    baseline_label,
    diff_cell,
    json_safe,
    legend,
    markdown_table,
    mean_ci_cell,
)
from rtaw_marl.evaluation.stats import mean_ci
from rtaw_marl.evaluation.tidy import csv_text
from rtaw_marl.utils.atomic import disk_full_guard
from rtaw_marl.utils.signals import signals_held

__all__ = [
    "EPISODES",
    "OUTPUT_NAMES",
    "OUTPUT_STEM",
    "OUTPUT_SUFFIXES",
    "CombinedFiles",
    "combined_paths",
    "combined_payload",
    "combined_table",
    "episodes_csv",
    "render_combined",
    "write_combined",
]

#: The combined files are ``<folder>/combined.{txt,csv,json,png}`` and
#: ``<folder>/combined_episodes.csv``.
OUTPUT_STEM = "combined"
#: The suffixes of the ``combined.*`` files, in the order they are listed.
OUTPUT_SUFFIXES = ("txt", "csv", "json", "png")
#: The key of the per-episode table among the files.
EPISODES = "episodes"
#: Every combined file's name by its key: the suffixes, and :data:`EPISODES`.
OUTPUT_NAMES = {
    **{suffix: f"{OUTPUT_STEM}.{suffix}" for suffix in OUTPUT_SUFFIXES},
    EPISODES: f"{OUTPUT_STEM}_episodes.csv",
}


def combined_paths(folder: str | Path) -> dict[str, Path]:
    """The combined files of ``folder`` by key (:data:`OUTPUT_NAMES`)."""
    return {key: Path(folder) / name for key, name in OUTPUT_NAMES.items()}


def combined_table(combined: Combined, confidence: float = 0.95) -> str:
    """A markdown table, one row per policy and setting, and ``rtaw-eval``'s legend.

    Columns: the swept keys, the policy, the number of seeds, the metric's mean ± the
    half-width of its t-interval, then its paired difference with each baseline (``+``
    = better than the baseline: below its TTD, above its tasks finished) as
    ``rtaw-eval`` prints it.
    """
    level = f"{100 * confidence:g}% CI"
    label = metric_label(combined.metric)
    head = [*combined.swept, "policy", "seeds", f"{label} ± {level}"]
    head += [f"{label} vs {baseline_label(base)}" for base in combined.baselines]
    rows = []
    for row in combined.rows:
        cells = [*row.setting.values(), row.policy, str(len(row.seeds))]
        cells.append(mean_ci_cell(row.values, confidence))
        cells += [diff_cell(row.vs[b]) if b in row.vs else "—" for b in combined.baselines]
        rows.append(cells)
    n = min(len(row.seeds) for row in combined.rows)
    note = legend(n, confidence, combined.baselines, False, "", combined.metric)
    return markdown_table(head, rows) + "\n" + note


def _interval(values: Sequence[float], confidence: float) -> tuple[float, list[float] | None]:
    mean, half = mean_ci(values, confidence)
    return mean, None if half is None else [mean - half, mean + half]


def combined_payload(combined: Combined, confidence: float = 0.95) -> dict[str, Any]:
    """The combined rows as a JSON-ready dict: the metric (``metric``, and ``goal``:
    ``"lower"``, ``"higher"`` or ``None``, which way is better), what every job shares
    (``fixed``), and per row its setting, policy, seeds, the metric per seed (under its
    name: ``ttd``), its mean (``ttd_mean``), interval (``ttd_ci``) and comparisons
    (``PairedDiff.as_dict()``)."""
    metric = combined.metric
    rows = []
    for row in combined.rows:
        mean, ci = _interval(row.values, confidence)
        rows.append(
            {
                "setting": row.setting,
                "policy": row.policy,
                "seeds": row.seeds,
                metric: row.values,
                f"{metric}_mean": mean,
                f"{metric}_ci": ci,
                "vs": {base: diff.as_dict() for base, diff in row.vs.items()},
                "source": row.source,
            }
        )
    return {
        "swept": combined.swept,
        "metric": metric,
        "goal": metric_goal(metric),
        "fixed": combined.fixed,
        "baselines": combined.baselines,
        "confidence": confidence,
        "sources": combined.sources,
        "rows": rows,
    }


def _csv_text(combined: Combined, confidence: float) -> str:
    """One line per row; a comparison's columns are empty where it does not exist."""
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    metric = combined.metric
    head = [*combined.swept, "policy", "seeds", f"{metric}_mean"]
    head += [f"{metric}_ci_low", f"{metric}_ci_high"]
    for base in combined.baselines:
        head += [f"vs_{base}_pct", f"vs_{base}_pct_low", f"vs_{base}_pct_high"]
        head.append(f"vs_{base}_significant")
    writer.writerow([*head, "source"])
    for row in combined.rows:
        mean, ci = _interval(row.values, confidence)
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


def episodes_csv(combined: Combined) -> str:
    """The per-episode table: one line per job, policy and seed (in the order of the
    combined rows), the swept keys' values, ``policy``, ``seed``, every metric any
    results file holds (in first-seen order; an empty cell where a file has none or it
    was not finite) and the results file (``source``)."""
    metrics = list(dict.fromkeys(name for row in combined.rows for name in row.metrics))
    lines: list[dict[str, Any]] = []
    for row in combined.rows:
        for i, seed in enumerate(row.seeds):
            line: dict[str, Any] = {**row.setting, "policy": row.policy, "seed": seed}
            line.update({name: values[i] for name, values in row.metrics.items()})
            lines.append({**line, "source": row.source})
    return csv_text(lines, [*combined.swept, "policy", "seed", *metrics, "source"])


@dataclass
class CombinedFiles:
    """The combined files, rendered and not yet written (:func:`render_combined`).

    Attributes:
        paths: Each file's target by key (:func:`combined_paths`).
        contents: Each file's bytes by key.
        written: Whether :meth:`write` has renamed all of them in; set inside the block
            that defers SIGINT and SIGTERM, so a stop handled right after it sees it.
    """

    paths: dict[str, Path]
    contents: dict[str, bytes]
    written: bool = field(default=False)

    def write(self) -> dict[str, Path]:
        """Write every file to a temporary beside its target (fsynced), then rename all
        of them in with SIGINT and SIGTERM deferred (``signals_held``); returns
        the targets by key.

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
    folder: str | Path,
    combined: Combined,
    table: str,
    confidence: float = 0.95,
    x: str | None = None,
) -> CombinedFiles:
    """``combined.txt`` (``table``), ``.csv``, ``.json``, ``.png`` (``x``: the swept key
    on its x axis, :func:`~rtaw_marl.evaluation.combine_plot.plot_spec`) and
    ``combined_episodes.csv`` for ``folder``, rendered in memory; nothing is written
    yet (:meth:`CombinedFiles.write`).

    Raises:
        ConfigError: ``x`` is not a swept key.
    """
    payload = json_safe(combined_payload(combined, confidence))
    contents = {
        "txt": f"{table}\n".encode(),
        "csv": _csv_text(combined, confidence).encode(),
        "json": json.dumps(payload, indent=2, allow_nan=False).encode(),
        "png": plot_png(combined, confidence, x),
        EPISODES: episodes_csv(combined).encode(),
    }
    return CombinedFiles(combined_paths(folder), contents)


def write_combined(
    folder: str | Path,
    combined: Combined,
    table: str,
    confidence: float = 0.95,
    x: str | None = None,
) -> dict[str, Path]:
    """Render and write the combined files (:func:`render_combined`) into ``folder`` as
    one set (:meth:`CombinedFiles.write`); returns them by key."""
    return render_combined(folder, combined, table, confidence, x).write()


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
