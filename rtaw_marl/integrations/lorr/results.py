"""``rtaw-lorr``'s results.json: written after every scheduler, read back to resume.

A run of several schedulers takes ``timesteps x plan_time_ms`` each, so a stop must not
lose the finished ones: the file is rewritten (atomically) after each ``lifelong`` run,
with the schedulers still to run under ``pending``. ``resume=true`` reads it back, keeps
the runs it holds when the setting is the same, and runs the rest.
"""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from rtaw_marl.errors import ConfigError
from rtaw_marl.integrations.lorr.config import LoRRConfig
from rtaw_marl.integrations.lorr.run import LoRRRun
from rtaw_marl.sim.lorr import LoRRProblem
from rtaw_marl.utils.atomic import atomic_write

__all__ = ["SETTING_KEYS", "SIMULATOR", "describe", "finished_runs", "write_results"]

#: The simulator a results file comes from.
SIMULATOR = "lorr-start-kit-2.1.2"

#: The config keys a resumed run must share with the file it continues: what changes a
#: scheduler's count (not the list of schedulers, where the output goes, or the kit's
#: cache).
SETTING_KEYS = (
    "timesteps", "plan_time_ms", "preprocess_time_ms", "share", "candidates", "baselines",
    "planner", "overflow",
)  # fmt: skip
#: Keys results files written before they existed lack: their values then.
_BEFORE = {"planner": "default", "overflow": "wait"}


def write_results(
    path: Path,
    cfg: LoRRConfig,
    problem: LoRRProblem,
    runs: dict[str, LoRRRun],
    pending: Iterable[str],
) -> None:
    """Write the runs so far (atomically: a stop while writing keeps the previous file)."""
    results = {
        "config": dataclasses.asdict(cfg),
        "problem": str(problem.path),
        "simulator": SIMULATOR,
        "runs": {label: dataclasses.asdict(run) for label, run in runs.items()},
        "pending": list(pending),
    }
    text = json.dumps(results, indent=1)
    atomic_write(path, lambda fh: fh.write(text.encode()))


def finished_runs(path: Path, cfg: LoRRConfig, problem: LoRRProblem) -> dict[str, LoRRRun]:
    """The runs of a results file to continue (``resume=true``); none if it is missing.

    Raises:
        ConfigError: The file is not an rtaw-lorr results file, or its setting (problem,
            a key of :data:`SETTING_KEYS`) differs from this run's; the key is named.
    """
    if not path.exists():
        return {}
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
        old_cfg, runs = data["config"], data["runs"]
        old_problem = data["problem"]
        kept = {label: LoRRRun(**run) for label, run in runs.items()}
    except (OSError, UnicodeDecodeError, ValueError, KeyError, TypeError, RecursionError):
        raise ConfigError(
            f"resume=true: {path} is not an rtaw-lorr results file; give another output"
        ) from None
    if old_problem != str(problem.path):
        raise ConfigError(
            f"resume=true: {path} holds runs of problem {old_problem}, not {problem.path}"
        )
    now = dataclasses.asdict(cfg)
    for key in SETTING_KEYS:
        old = old_cfg.get(key, _BEFORE.get(key))
        if old != now[key]:
            raise ConfigError(
                f"resume=true: {path} was run with {key}={old!r}, this run has "
                f"{key}={now[key]!r}; resume with the same setting or give another output"
            )
    return kept


def describe(runs: dict[str, Any]) -> str:
    """``"mpdm and rbts"``: the labels, for a message."""
    labels = list(runs)
    if len(labels) <= 1:
        return "".join(labels)
    return f"{', '.join(labels[:-1])} and {labels[-1]}"
