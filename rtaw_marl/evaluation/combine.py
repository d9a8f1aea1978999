"""Combine the ``results.json`` files of a sweep (``rtaw-eval -m``) into one table.

Each job of a sweep writes its own ``results.json``. :func:`load_jobs` finds them under
the folders given, :func:`combine` groups their rows by *setting* (the config without
the options that do not change an episode, :data:`~rtaw_marl.evaluation.journal.
NOT_SETTING`) and names each setting by the overrides that differ between jobs (the
job's ``.hydra/overrides.yaml``; without it, the config keys that differ). Jobs of one
setting (a sweep over ``policy``) are merged when they ran the same seeds. Every number
is recomputed from the per-seed values exactly as ``rtaw-eval`` computes its own
(:func:`~rtaw_marl.evaluation.stats.mean_ci`,
:func:`~rtaw_marl.evaluation.stats.paired_difference`), on TTD or any other metric the
files hold (:func:`check_metric`), signed by which way it is better
(:mod:`~rtaw_marl.evaluation.metric_goals`).
"""

from __future__ import annotations

import json
import re
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, cast

from rtaw_marl.errors import ConfigError, did_you_mean
from rtaw_marl.evaluation.job_overrides import job_overrides
from rtaw_marl.evaluation.journal import NOT_SETTING
from rtaw_marl.evaluation.metric_goals import metric_difference
from rtaw_marl.evaluation.results_file import read_results
from rtaw_marl.evaluation.stats import PairedDiff

__all__ = [
    "RESULTS_NAME",
    "Combined",
    "Job",
    "Row",
    "check_metric",
    "combine",
    "evaluated_policies",
    "find_results",
    "load_jobs",
    "metric_names",
]

#: The file every ``rtaw-eval`` job writes in its folder.
RESULTS_NAME = "results.json"

#: The config keys that name a setting in a plot's title, when the same in every job
#: (a group by its option's name: ``layout=shelves``); the jobs' other common overrides
#: follow them.
HEADLINE_KEYS = (
    "layout.name", "navigator.name", "tasks.name", "sim.num_robots", "sim.num_tasks",
    "sim.episode_mode", "sim.horizon",
)  # fmt: skip


@dataclass(frozen=True)
class Job:
    """One ``results.json``.

    Attributes:
        path: The file.
        setting: Its flattened config without :data:`NOT_SETTING` (dotted keys, JSON
            values): what makes two jobs' episodes comparable.
        overrides: Its job's command-line overrides by key (``None``: no
            ``.hydra/overrides.yaml`` beside it).
        seeds: The episode seeds.
        policies: ``{policy: {metric: [per seed]}}`` (TTD always a number; another
            metric may be ``None`` where it was not finite).
    """

    path: Path
    setting: dict[str, str]
    overrides: dict[str, str] | None
    seeds: list[int]
    policies: dict[str, dict[str, list[float | None]]]


@dataclass
class Row:
    """One policy at one setting.

    Attributes:
        setting: The swept keys' values.
        policy: The policy's name.
        seeds: The seeds.
        values: The compared metric (:attr:`Combined.metric`) per seed.
        vs: Paired comparisons of that metric with each baseline evaluated at this
            setting (positive: this policy is better, or has more of a metric with no
            better side).
        source: The results file.
        metrics: Every metric of the results file per seed (``None`` where it was not
            finite), for the per-episode table.
    """

    setting: dict[str, str]
    policy: str
    seeds: list[int]
    values: list[float]
    vs: dict[str, PairedDiff] = field(default_factory=dict)
    source: str = ""
    metrics: dict[str, list[float | None]] = field(default_factory=dict)


@dataclass
class Combined:
    """The combined rows and what they were combined from.

    Attributes:
        swept: The keys that name a setting (may be empty: one setting).
        rows: Setting by setting, the policies in the order the jobs list them.
        baselines: The policies every row is compared with (evaluated somewhere).
        sources: The results files read.
        metric: The metric of :attr:`Row.values` and the comparisons.
        fixed: What every job shares, in short (:data:`HEADLINE_KEYS` and the common
            overrides), as ``{key: value}`` to type on the command line.
    """

    swept: list[str]
    rows: list[Row]
    baselines: list[str]
    sources: list[str]
    metric: str = "ttd"
    fixed: dict[str, str] = field(default_factory=dict)


def find_results(paths: Iterable[str | Path]) -> list[Path]:
    """Every ``results.json`` under the folders in ``paths``, and the files named.

    Raises:
        ConfigError: A path does not exist, or nothing was found.
    """
    found: dict[Path, None] = {}
    for path in map(Path, paths):
        if path.is_file():
            found[path.resolve()] = None
        elif path.is_dir():
            for hit in sorted(path.rglob(RESULTS_NAME), key=_natural):
                found[hit.resolve()] = None
        else:
            raise ConfigError(f"no such file or folder: {path}")
    if not found:
        raise ConfigError(
            f"no {RESULTS_NAME} under {', '.join(map(str, paths))} (rtaw-eval -m writes "
            "one per job)"
        )
    return list(found)


def _natural(path: Path) -> list[Any]:
    """Job folders in number order (``2`` before ``10``)."""
    return [int(p) if p.isdigit() else p for p in re.split(r"(\d+)", str(path))]


def load_jobs(paths: Iterable[str | Path]) -> list[Job]:
    """The jobs of :func:`find_results`, each file checked in full
    (:func:`~rtaw_marl.evaluation.results_file.read_results`) before any is used.

    Raises:
        ConfigError: A file is not readable JSON or not an ``rtaw-eval`` results file,
            or a job's ``.hydra/overrides.yaml`` is not a list of overrides.
    """
    return [_load(path) for path in find_results(paths)]


def _load(path: Path) -> Job:
    results = read_results(path)  # the whole file checked before any of it is used
    setting = {k: v for k, v in results.config.items() if k not in NOT_SETTING}
    policies = {name: dict(metrics) for name, metrics in results.policies.items()}
    return Job(path, dict(_flatten(setting)), job_overrides(path), results.seeds, policies)


def evaluated_policies(jobs: Sequence[Job]) -> list[str]:
    """Every policy some job evaluated, in the order they first appear."""
    return list(dict.fromkeys(name for job in jobs for name in job.policies))


def metric_names(jobs: Sequence[Job]) -> list[str]:
    """The metrics every policy of every job holds, in the order the first lists them."""
    held = [set(m) for job in jobs for m in job.policies.values()]
    first = next(iter(jobs[0].policies.values())) if jobs else {}
    return [name for name in first if all(name in h for h in held)]


def check_metric(jobs: Sequence[Job], metric: str) -> None:
    """Check that every policy of every job has a number for ``metric`` on every seed.

    Raises:
        ConfigError: ``metric`` is not held by every policy of every job (the message
            lists those that are), or one of its values is ``null`` (not finite).
    """
    valid = metric_names(jobs)
    if metric not in valid:
        some = [f"{job.path} ({p})" for job in jobs for p, m in job.policies.items() if metric in m]
        held = f"held only by some results ({some[0]} ...), not all; " if some else ""
        raise ConfigError(
            f"--metric {metric}: {held or 'unknown metric; '}valid: {', '.join(valid)}"
            f"{'' if some else did_you_mean(metric, valid)}"
        )
    for job in jobs:
        for policy, metrics in job.policies.items():
            if None in metrics[metric]:
                seed = job.seeds[metrics[metric].index(None)]
                raise ConfigError(
                    f"--metric {metric}: {job.path}: policy {policy} has no finite "
                    f"{metric} on seed {seed} (null); compare another metric"
                )


def _flatten(config: Mapping[str, Any], prefix: str = "") -> Iterable[tuple[str, str]]:
    for key, value in config.items():
        if isinstance(value, Mapping):
            yield from _flatten(value, f"{prefix}{key}.")
        else:
            yield f"{prefix}{key}", json.dumps(value, sort_keys=True)


def _swept(jobs: Sequence[Job], settings: Sequence[dict[str, str]]) -> list[str]:
    """The keys that name each distinct setting: the overrides that differ between
    jobs when every job has them and they tell the settings apart, else the config
    keys that differ."""
    distinct = {json.dumps(s, sort_keys=True) for s in settings}
    if all(job.overrides is not None for job in jobs):
        keys = _differing([job.overrides or {} for job in jobs])
        labels = {tuple((job.overrides or {}).get(k, "") for k in keys) for job in jobs}
        if len(labels) == len(distinct):
            return keys
    return _differing(settings)


def _differing(dicts: Sequence[Mapping[str, str]]) -> list[str]:
    keys = list(dict.fromkeys(k for d in dicts for k in d))
    return [k for k in keys if len({d.get(k) for d in dicts}) > 1]


def _label(job: Job, key: str) -> str:
    if job.overrides is not None and key in job.overrides:
        return job.overrides[key]
    value = job.setting.get(key)
    if value is None:
        return "(default)"
    loaded = json.loads(value)
    return loaded if isinstance(loaded, str) else value


def combine(
    jobs: Sequence[Job],
    reference: str = "mpdm",
    compare_to: str | None = None,
    confidence: float = 0.95,
    metric: str = "ttd",
) -> Combined:
    """Group the jobs' rows by setting and compare every policy with the baselines.

    Args:
        jobs: From :func:`load_jobs`.
        reference: The main baseline (``rtaw-eval``'s MPDM); skipped where it was not
            evaluated, like ``rtaw-eval``'s.
        compare_to: A second baseline, like ``rtaw-eval``'s ``compare_to``; it must be
            evaluated in some job.
        confidence: Confidence level of the intervals.
        metric: The metric to compare (:func:`check_metric`).

    Raises:
        ConfigError: Two jobs of one setting hold the same policy or other seeds, a
            baseline asked for was evaluated nowhere, or ``metric`` is not a number on
            every seed of every policy.
    """
    check_metric(jobs, metric)
    swept = _swept(jobs, [job.setting for job in jobs])
    groups: dict[str, list[Job]] = {}
    for job in jobs:
        groups.setdefault(json.dumps(job.setting, sort_keys=True), []).append(job)
    evaluated = evaluated_policies(jobs)
    if compare_to is not None and compare_to not in evaluated:
        raise ConfigError(
            f"compare_to {compare_to} was evaluated in no job; evaluated: {', '.join(evaluated)}"
        )
    baselines = [b for b in dict.fromkeys([reference, compare_to]) if b in evaluated]
    rows: list[Row] = []
    for group in groups.values():
        rows += _group_rows(group, swept, baselines, confidence, metric)
    sources = [str(job.path) for job in jobs]
    return Combined(swept, rows, baselines, sources, metric, _fixed(jobs, swept))


def _group_rows(
    group: Sequence[Job],
    swept: Sequence[str],
    baselines: Sequence[str],
    confidence: float,
    metric: str,
) -> list[Row]:
    """The rows of the jobs of one setting (merged), compared with the baselines."""
    first = group[0]
    setting = {key: _label(first, key) for key in swept}
    named = " ".join(f"{k}={v}" for k, v in setting.items()) or "the setting"
    rows: dict[str, Row] = {}
    for job in group:
        if job.seeds != first.seeds:
            raise ConfigError(
                f"{named}: {first.path} has seeds {first.seeds}, {job.path} {job.seeds}; "
                "paired comparisons need the same seeds"
            )
        for name, metrics in job.policies.items():
            if name in rows:
                raise ConfigError(
                    f"{named}: policy {name} is in {rows[name].source} and {job.path}"
                )
            values = [float(v) for v in cast("list[float]", metrics[metric])]  # checked
            rows[name] = Row(dict(setting), name, list(first.seeds), values, source=str(job.path),
                             metrics={k: list(v) for k, v in metrics.items()})  # fmt: skip
    for name, row in rows.items():
        for base in baselines:
            if base in rows and base != name:
                row.vs[base] = metric_difference(metric, rows[base].values, row.values, confidence)
    return list(rows.values())


def _fixed(jobs: Sequence[Job], swept: Sequence[str]) -> dict[str, str]:
    """What every job shares, short: the :data:`HEADLINE_KEYS` of one value in every job
    (a group as ``layout=shelves``), then the overrides every job has alike, each by the
    key to type; none under a swept key."""

    def under_swept(key: str) -> bool:
        return any(key == s or key.startswith(f"{s}.") or s.startswith(f"{key}.") for s in swept)

    fixed: dict[str, str] = {}
    for key in HEADLINE_KEYS:
        values = {job.setting.get(key) for job in jobs}
        value = values.pop() if len(values) == 1 else None
        if value is not None and value != "null" and not under_swept(key):
            loaded = json.loads(value)
            fixed[key.removesuffix(".name")] = loaded if isinstance(loaded, str) else value
    if all(job.overrides is not None for job in jobs):
        common = [job.overrides or {} for job in jobs]
        for key, value in common[0].items():
            if (
                key not in fixed
                and not under_swept(key)
                and all(o.get(key) == value for o in common)
            ):
                fixed[key] = value
    return fixed
