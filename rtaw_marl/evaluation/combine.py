"""Combine the ``results.json`` files of a sweep (``rtaw-eval -m``) into one table.

Each job of a sweep writes its own ``results.json``. :func:`load_jobs` finds them under
the folders given, :func:`combine` groups their rows by *setting* (the config without
the options that do not change an episode, :data:`~rtaw_marl.evaluation.journal.
NOT_SETTING`) and names each setting by the overrides that differ between jobs (the
job's ``.hydra/overrides.yaml``; without it, the config keys that differ). Jobs of one
setting (a sweep over ``policy``) are merged when they ran the same seeds. Every number
is recomputed from the per-seed values exactly as ``rtaw-eval`` computes its own
(:func:`~rtaw_marl.evaluation.stats.mean_ci`,
:func:`~rtaw_marl.evaluation.stats.paired_difference`).
"""

from __future__ import annotations

import json
import re
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from rtaw_marl.errors import ConfigError
from rtaw_marl.evaluation.journal import NOT_SETTING
from rtaw_marl.evaluation.results_file import read_results
from rtaw_marl.evaluation.stats import PairedDiff, paired_difference
from rtaw_marl.utils.renamed import upgrade_command

__all__ = [
    "RESULTS_NAME",
    "Combined",
    "Job",
    "Row",
    "combine",
    "evaluated_policies",
    "find_results",
    "load_jobs",
]

#: The file every ``rtaw-eval`` job writes in its folder.
RESULTS_NAME = "results.json"


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
        ttd: TTD per seed.
        vs: Paired TTD comparisons with each baseline evaluated at this setting.
        source: The results file.
    """

    setting: dict[str, str]
    policy: str
    seeds: list[int]
    ttd: list[float]
    vs: dict[str, PairedDiff] = field(default_factory=dict)
    source: str = ""


@dataclass
class Combined:
    """The combined rows and what they were combined from.

    Attributes:
        swept: The keys that name a setting (may be empty: one setting).
        rows: Setting by setting, the policies in the order the jobs list them.
        baselines: The policies every row is compared with (evaluated somewhere).
        sources: The results files read.
    """

    swept: list[str]
    rows: list[Row]
    baselines: list[str]
    sources: list[str]


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
    return Job(path, dict(_flatten(setting)), _overrides(path), results.seeds, policies)


def evaluated_policies(jobs: Sequence[Job]) -> list[str]:
    """Every policy some job evaluated, in the order they first appear."""
    return list(dict.fromkeys(name for job in jobs for name in job.policies))


def _flatten(config: Mapping[str, Any], prefix: str = "") -> Iterable[tuple[str, str]]:
    for key, value in config.items():
        if isinstance(value, Mapping):
            yield from _flatten(value, f"{prefix}{key}.")
        else:
            yield f"{prefix}{key}", json.dumps(value, sort_keys=True)


def _overrides(path: Path) -> dict[str, str] | None:
    """The job's overrides (``.hydra/overrides.yaml``) by key, without the options
    that are no setting; ``None`` when the file is not there. Overrides written before
    the simulator's keys were renamed (``env.num_robots=10``) are read under today's
    names (``sim.num_robots``), as the results file's config is.

    Raises:
        ConfigError: The file cannot be read, or is not what Hydra writes there (a list
            of ``KEY=VALUE`` strings); the message names it.
    """
    file = path.parent / ".hydra" / "overrides.yaml"
    if not file.is_file():
        return None
    out: dict[str, str] = {}
    for item in upgrade_command(_override_items(file)):
        key, _, value = item.partition("=")
        key = key.lstrip("+~")
        if key.split(".")[0].split("/")[0] not in (*NOT_SETTING, "hydra"):
            out[key] = value
    return out


def _override_items(file: Path) -> list[str]:
    """The strings of an overrides file, checked: Hydra writes a list of them."""
    import yaml  # omegaconf's dependency: the cli extra

    try:
        items = yaml.safe_load(file.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, yaml.YAMLError) as exc:
        raise ConfigError(f"{file}: cannot be read ({_first_line(exc)})") from None
    except RecursionError:  # PyYAML composes nested nodes recursively
        raise ConfigError(f"{file}: nested too deeply to be a Hydra overrides list") from None
    if items is None:  # an empty file: a job run without overrides
        return []
    if not isinstance(items, list) or not all(isinstance(item, str) for item in items):
        raise ConfigError(
            f"{file}: not a Hydra overrides list (a list of KEY=VALUE strings, as "
            "Hydra writes for each job)"
        )
    return items


def _first_line(exc: BaseException) -> str:
    return (str(exc).strip().splitlines() or [type(exc).__name__])[0]


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
) -> Combined:
    """Group the jobs' rows by setting and compare every policy with the baselines.

    Args:
        jobs: From :func:`load_jobs`.
        reference: The main baseline (``rtaw-eval``'s MPDM); skipped where it was not
            evaluated, like ``rtaw-eval``'s.
        compare_to: A second baseline, like ``rtaw-eval``'s ``compare_to``; it must be
            evaluated in some job.
        confidence: Confidence level of the intervals.

    Raises:
        ConfigError: Two jobs of one setting hold the same policy or other seeds, or a
            baseline asked for was evaluated nowhere.
    """
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
        rows += _group_rows(group, swept, baselines, confidence)
    return Combined(swept, rows, baselines, [str(job.path) for job in jobs])


def _group_rows(
    group: Sequence[Job], swept: Sequence[str], baselines: Sequence[str], confidence: float
) -> list[Row]:
    """The rows of the jobs of one setting (merged), compared with the baselines."""
    first = group[0]
    setting = {key: _label(first, key) for key in swept}
    named = " ".join(f"{k}={v}" for k, v in setting.items()) or "the setting"
    ttd: dict[str, list[float]] = {}
    source: dict[str, str] = {}
    for job in group:
        if job.seeds != first.seeds:
            raise ConfigError(
                f"{named}: {first.path} has seeds {first.seeds}, {job.path} {job.seeds}; "
                "paired comparisons need the same seeds"
            )
        for name, metrics in job.policies.items():
            if name in ttd:
                raise ConfigError(f"{named}: policy {name} is in {source[name]} and {job.path}")
            ttd[name] = [float(v) for v in metrics["ttd"]]
            source[name] = str(job.path)
    rows = []
    for name, values in ttd.items():
        row = Row(dict(setting), name, list(first.seeds), values, source=source[name])
        for base in baselines:
            if base in ttd and base != name:
                row.vs[base] = paired_difference(ttd[base], values, confidence)
        rows.append(row)
    return rows
