"""Evaluation of policies on seeded episodes, paired statistics, tables and result files."""

from __future__ import annotations

from rtaw_marl.evaluation.evaluate import evaluate, run_episode
from rtaw_marl.evaluation.report import (
    comparisons,
    format_table,
    improvement,
    json_safe,
    write_json_atomic,
)
from rtaw_marl.evaluation.stats import (
    HindsightShare,
    PairedDiff,
    hindsight_share,
    mean_ci,
    paired_difference,
)

__all__ = [
    "HindsightShare",
    "PairedDiff",
    "comparisons",
    "evaluate",
    "format_table",
    "hindsight_share",
    "improvement",
    "json_safe",
    "mean_ci",
    "paired_difference",
    "run_episode",
    "write_json_atomic",
]
