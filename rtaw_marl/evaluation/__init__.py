"""Evaluation of policies on seeded episodes, tables and result files."""

from __future__ import annotations

from rtaw_marl.evaluation.evaluate import evaluate, run_episode
from rtaw_marl.evaluation.report import format_table, improvement, write_json_atomic

__all__ = ["evaluate", "format_table", "improvement", "run_episode", "write_json_atomic"]
