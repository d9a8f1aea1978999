"""Evaluation of policies on seeded episodes, paired statistics, tables and result files.

:func:`compare` is the one call for a user's policy against the rules (paired 95%
intervals); :func:`evaluate` plays given policies on given seeds of one simulator.
"""

from __future__ import annotations

from rtaw_marl.evaluation.best_rule import SELECTION_SEEDS, BestRule, choose_best_rule
from rtaw_marl.evaluation.compare import DEFAULT_RULES, Comparison, compare
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
    "DEFAULT_RULES",
    "SELECTION_SEEDS",
    "BestRule",
    "Comparison",
    "HindsightShare",
    "PairedDiff",
    "choose_best_rule",
    "compare",
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
