"""The one result schema: what ``rtaw-eval`` writes as ``results.json`` and what
``rtaw-results`` (and any reader) may rely on.

    {
      "config":  the evaluation's resolved config (JSON),
      "seeds":   [episode seeds],
      "policies": {label: {metric: [one value per seed]}},
      "comparisons": {label: {baseline: paired TTD difference}},
      "best_rule": {name, metric, scores, seeds}    (compare_to=best only)
      "lower_bound": [per seed] or null,
      "lower_bound_time_s": seconds or null
    }

The same per-episode values as a tidy table are ``results.csv``
(:mod:`rtaw_marl.evaluation.tidy`). :func:`read_results` is the one reader: it checks a
file in full (:func:`check_results`) before any of it is used, and names the file in
its one-line error. A file written before the simulator's config group was renamed
``sim`` holds its keys under ``config.env``: it is read under today's names
(:func:`upgrade_payload`), so old and new files combine.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from rtaw_marl.errors import ConfigError
from rtaw_marl.evaluation.report import comparisons
from rtaw_marl.policies.labels import upgrade_label
from rtaw_marl.sim.inputs import seed_list
from rtaw_marl.utils.renamed import upgrade_config

__all__ = [
    "MAX_DEPTH",
    "REQUIRED_KEYS",
    "ResultsFile",
    "check_results",
    "read_results",
    "results_payload",
    "upgrade_payload",
]

#: The keys every results file has (a reader refuses a file without them).
REQUIRED_KEYS = ("config", "seeds", "policies")

#: How deep a results file may nest. Its deepest entries (a comparison's interval,
#: ``comparisons.<policy>.vs.<baseline>.ci``) are 6 levels down and a config's groups a
#: few more; a deeper file is no results file, and would make the readers that recurse
#: (JSON's, the config's flattening) hit Python's recursion limit.
MAX_DEPTH = 32


def results_payload(
    config: Mapping[str, Any],
    seeds: Sequence[int],
    results: Mapping[str, Mapping[str, Sequence[float]]],
    reference: str,
    compare_to: str | None = None,
    lower_bound: Sequence[float] | None = None,
    lower_bound_time_s: float | None = None,
    best_rule: Mapping[str, Any] | None = None,
) -> dict[str, Any]:
    """The ``results.json`` object of an evaluation.

    Args:
        config: The resolved config (plain JSON values).
        seeds: The episode seeds, in the order of every per-seed list.
        results: ``{label: {metric: [per seed]}}`` (:func:`~rtaw_marl.evaluation.evaluate`).
        reference: The main baseline of the comparisons (MPDM).
        compare_to: A second baseline, or None.
        lower_bound: The TTD lower bound per seed, when computed.
        lower_bound_time_s: What computing it took.
        best_rule: With ``compare_to=best``, how the bar was chosen
            (:meth:`~rtaw_marl.evaluation.best_rule.BestRule.as_dict`); stored as
            ``best_rule``.
    """
    extra = {} if best_rule is None else {"best_rule": dict(best_rule)}
    return {
        "config": dict(config),
        "seeds": list(seeds),
        "lower_bound": None if lower_bound is None else list(lower_bound),
        "lower_bound_time_s": lower_bound_time_s,
        "policies": {name: dict(metrics) for name, metrics in results.items()},
        "comparisons": comparisons(results, reference, compare_to=compare_to),
        **extra,
    }


@dataclass(frozen=True)
class ResultsFile:
    """A ``results.json``, read and checked in full by :func:`read_results`.

    Attributes:
        path: The file.
        config: The evaluation's resolved config, under today's names (an old file's
            ``env`` section is ``sim``).
        seeds: The episode seeds: distinct integers >= 0.
        policies: ``{policy: {metric: [one value per seed]}}``; every ``ttd`` value a
            finite number, every other metric's a finite number or ``null``.
        comparisons: ``{policy: {...}}`` as ``rtaw-eval`` wrote them (``{}`` when absent).
        lower_bound: The TTD lower bound per seed, or None.
        lower_bound_time_s: What computing it took, or None.
    """

    path: Path
    config: dict[str, Any]
    seeds: list[int]
    policies: dict[str, dict[str, list[float | None]]]
    comparisons: dict[str, Any]
    lower_bound: list[float] | None
    lower_bound_time_s: float | None


def read_results(path: str | Path) -> ResultsFile:
    """Read a ``results.json`` and check all of it before any of it is used.

    The one reader of the schema: every other reader (``rtaw-results``) goes through it.

    Raises:
        ConfigError: The file cannot be read, is not strict JSON, nests deeper than
            :data:`MAX_DEPTH`, or breaks the schema (:func:`check_results`); the
            message names the file.
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise ConfigError(f"{path}: cannot be read ({_reason(exc)})") from None
    try:
        data = json.loads(text, parse_constant=_no_constant)
    except ValueError as exc:  # a JSONDecodeError, or NaN or Infinity (_no_constant)
        raise ConfigError(f"{path}: cannot be read as JSON ({exc})") from None
    except RecursionError:
        # The parser recurses once per level: a file nested thousands deep is no results
        # file, and the limit it hit is the interpreter's, not a fact about the file.
        raise ConfigError(_too_deep(path)) from None
    return check_results(data, path)


def upgrade_payload(data: Mapping[str, Any]) -> dict[str, Any]:
    """A loaded results file under today's names: a ``config`` written before the
    simulator's group was renamed (``config.env``) has it as ``config.sim``, in the same
    place, and a policy labelled before labels were short (``rtaw:generalist_plus``) has
    today's label (:func:`~rtaw_marl.policies.labels.upgrade_label`); anything else comes
    back as it was (a shallow copy)."""
    out = dict(data)
    if isinstance(out.get("config"), Mapping):
        out["config"] = upgrade_config(out["config"])
    if isinstance(out.get("policies"), Mapping):
        out["policies"] = {upgrade_label(k): v for k, v in out["policies"].items()}
    return out


def check_results(data: Any, path: str | Path) -> ResultsFile:
    """``data``, a loaded results file, checked in full; its config under today's names
    (:func:`upgrade_payload`).

    Raises:
        ConfigError: It nests deeper than :data:`MAX_DEPTH`, a required key is missing,
            ``config`` is no object, ``seeds`` are not distinct integers >= 0, a policy
            has no finite TTD per seed, a metric has no value per seed, or the optional
            entries have the wrong shape.
    """
    path = Path(path)
    # First, without recursion: everything after (and every user of the file) may recurse.
    if _depth(data) > MAX_DEPTH:
        raise ConfigError(_too_deep(path))
    if not isinstance(data, dict) or not set(REQUIRED_KEYS) <= set(data):
        raise ConfigError(f"{path}: not an rtaw-eval results file ({', '.join(REQUIRED_KEYS)})")
    if not isinstance(data["config"], dict):
        raise ConfigError(f"{path}: config is {_kind(data['config'])}, not an object")
    data = upgrade_payload(data)
    try:
        seeds = seed_list(data["seeds"], "seeds")
    except ConfigError as exc:
        raise ConfigError(f"{path}: {exc}") from None
    policies = _policies(data["policies"], len(seeds), path)
    comparisons = data.get("comparisons", {})
    if not isinstance(comparisons, dict) or not all(
        isinstance(v, dict) for v in comparisons.values()
    ):
        raise ConfigError(f"{path}: comparisons is not an object of one object per policy")
    bound, bound_time = data.get("lower_bound"), data.get("lower_bound_time_s")
    if bound is not None and not (
        isinstance(bound, list) and len(bound) == len(seeds) and all(map(_number, bound))
    ):
        raise ConfigError(f"{path}: lower_bound is not null or one number per seed")
    if bound_time is not None and not (_number(bound_time) and bound_time >= 0):
        raise ConfigError(f"{path}: lower_bound_time_s is not null or a number >= 0")
    return ResultsFile(path, data["config"], seeds, policies, comparisons, bound, bound_time)


def _policies(policies: Any, n: int, path: Path) -> dict[str, dict[str, list[float | None]]]:
    """``policies`` checked: an object of policies, each an object of per-seed lists."""
    if not isinstance(policies, dict) or not policies:
        raise ConfigError(f"{path}: policies is not an object of one or more policies")
    for name, metrics in policies.items():
        ttd = metrics.get("ttd") if isinstance(metrics, dict) else None
        if not isinstance(ttd, list) or len(ttd) != n or not all(map(_number, ttd)):
            raise ConfigError(f"{path}: policy {name} has no TTD per seed ({n} seeds)")
        for metric, values in metrics.items():
            if (
                not isinstance(values, list)
                or len(values) != n
                or not all(v is None or _number(v) for v in values)
            ):
                raise ConfigError(
                    f"{path}: policy {name}: metric {metric} is not one number (or null) "
                    f"per seed ({n} seeds)"
                )
    return policies


def _depth(data: Any) -> int:
    """How deep ``data`` nests (a scalar 0, ``[]`` 1, ``[[]]`` 2), found iteratively and
    stopping once past :data:`MAX_DEPTH`."""
    deepest, stack = 0, [(data, 0)]
    while stack:
        value, depth = stack.pop()
        if isinstance(value, (dict, list)):
            depth += 1
            deepest = max(deepest, depth)
            if deepest > MAX_DEPTH:
                break
            stack.extend((v, depth) for v in (value.values() if isinstance(value, dict) else value))
    return deepest


def _too_deep(path: Path) -> str:
    return (
        f"{path}: nested more than {MAX_DEPTH} levels deep; not an rtaw-eval results file "
        "(its deepest entries are a few levels down)"
    )


def _no_constant(name: str) -> None:
    """``NaN``, ``Infinity``: not strict JSON, and never in a file ``rtaw-eval`` wrote
    (it writes ``null`` for a non-finite value)."""
    raise ValueError(f"{name} is not strict JSON")


def _reason(exc: OSError | UnicodeDecodeError) -> str:
    if isinstance(exc, OSError):
        return exc.strerror or type(exc).__name__
    return "not UTF-8 text"


def _kind(value: Any) -> str:
    """A JSON value's type, for a message (never a Python repr of the value)."""
    names = {dict: "an object", list: "a list", str: "a string", bool: "a boolean"}
    if value is None:
        return "null"
    return names.get(type(value), "a number")


def _number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
