"""The one result schema: what ``rtaw-eval`` writes as ``results.json`` and what
``rtaw-results`` (and any reader) may rely on.

    {
      "config":  the evaluation's resolved config (JSON),
      "seeds":   [episode seeds],
      "policies": {label: {metric: [one value per seed]}},
      "comparisons": {label: {baseline: paired TTD difference}},
      "lower_bound": [per seed] or null,
      "lower_bound_time_s": seconds or null
    }

The same per-episode values as a tidy table are ``results.csv``
(:mod:`rtaw_marl.evaluation.tidy`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from rtaw_marl.errors import ConfigError
from rtaw_marl.evaluation.report import comparisons

__all__ = ["REQUIRED_KEYS", "check_results", "results_payload"]

#: The keys every results file has (a reader refuses a file without them).
REQUIRED_KEYS = ("config", "seeds", "policies")


def results_payload(
    config: Mapping[str, Any],
    seeds: Sequence[int],
    results: Mapping[str, Mapping[str, Sequence[float]]],
    reference: str,
    compare_to: str | None = None,
    lower_bound: Sequence[float] | None = None,
    lower_bound_time_s: float | None = None,
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
    """
    return {
        "config": dict(config),
        "seeds": list(seeds),
        "lower_bound": None if lower_bound is None else list(lower_bound),
        "lower_bound_time_s": lower_bound_time_s,
        "policies": {name: dict(metrics) for name, metrics in results.items()},
        "comparisons": comparisons(results, reference, compare_to=compare_to),
    }


def check_results(data: Any, path: str | Path) -> tuple[list[int], dict[str, Any], dict]:
    """``(seeds, policies, config)`` of a loaded results file, checked.

    Raises:
        ConfigError: A required key is missing, or a policy has no finite TTD per seed.
    """
    if not isinstance(data, dict) or not set(REQUIRED_KEYS) <= set(data):
        raise ConfigError(f"{path}: not an rtaw-eval results file ({', '.join(REQUIRED_KEYS)})")
    seeds, policies = data["seeds"], data["policies"]
    if not isinstance(seeds, list) or not isinstance(policies, dict) or not policies:
        raise ConfigError(f"{path}: not an rtaw-eval results file (seeds, policies)")
    for name, metrics in policies.items():
        ttd = metrics.get("ttd") if isinstance(metrics, dict) else None
        if not isinstance(ttd, list) or len(ttd) != len(seeds) or not all(map(_number, ttd)):
            raise ConfigError(f"{path}: policy {name} has no TTD per seed ({len(seeds)} seeds)")
    config = data["config"] if isinstance(data["config"], dict) else {}
    return seeds, policies, config


def _number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
