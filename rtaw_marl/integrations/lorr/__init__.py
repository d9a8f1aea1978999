"""The League of Robot Runners (LoRR) 2024, in one place: every public LoRR name of the
project is importable from here.

The code itself sits by layer, because the simulator must read LoRR's files without
knowing LoRR's runner (no low layer knows a high one):

- the problem files (a problem's map, starts and tasks, its reveal window):
  :mod:`rtaw_marl.sim.lorr`, read by ``layout=lorr`` and ``tasks=lorr``; the simulator's
  one hook for LoRR's rule is the generic ``sim.refill=finish`` (a finished task's slot
  is refilled, so the revealed tasks include those in progress);
- a problem as a scenario (``scenario=lorr``, ``lorr_scenario(path)``):
  :mod:`rtaw_marl.scenarios.lorr`;
- LoRR's output format, written (:mod:`.output`) and read and checked (the one reader,
  :mod:`rtaw_marl.viz.schedule_file`);
- LoRR's own simulator: the start kit's build (:mod:`.kit`), one ``lifelong`` run
  (:mod:`.run`), the scheduler it loads (:mod:`.entry`, :mod:`.scheduler`),
  ``rtaw-lorr``'s options and results (:mod:`.config`, :mod:`.results`).

Names are loaded on first use, so ``import rtaw_marl.integrations.lorr`` stays light
(LoRR's own process imports :mod:`.entry` through this package).
"""

from __future__ import annotations

import importlib
from typing import Any

#: Public name -> the module that defines it.
_NAMES = {
    "LoRRProblem": "rtaw_marl.sim.lorr",
    "LoRRTasks": "rtaw_marl.sim.lorr",
    "read_problem": "rtaw_marl.sim.lorr",
    "reveal_window": "rtaw_marl.sim.lorr",
    "lorr_scenario": "rtaw_marl.scenarios.lorr",
    "episode_output": "rtaw_marl.integrations.lorr.output",
    "write_episode": "rtaw_marl.integrations.lorr.output",
    "read_schedule": "rtaw_marl.integrations.lorr.output",
    "replay": "rtaw_marl.integrations.lorr.output",
    "read_schedule_file": "rtaw_marl.viz.schedule_file",
    "build_kit": "rtaw_marl.integrations.lorr.kit",
    "StartKitError": "rtaw_marl.integrations.lorr.kit",
    "run_lifelong": "rtaw_marl.integrations.lorr.run",
    "read_output": "rtaw_marl.integrations.lorr.run",
    "LoRRRun": "rtaw_marl.integrations.lorr.run",
    "LoRRConfig": "rtaw_marl.integrations.lorr.config",
}

__all__ = sorted(_NAMES)


def __getattr__(name: str) -> Any:
    if name not in _NAMES:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(importlib.import_module(_NAMES[name]), name)


def __dir__() -> list[str]:
    return sorted({*globals(), *_NAMES})
