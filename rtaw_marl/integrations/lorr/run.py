"""One run of LoRR's ``lifelong`` with a chosen scheduler, read into the project's terms.

:func:`run_lifelong` makes the run folder (the run spec, the ``pyTaskScheduler.py``
that serves the policy, the kit's ``config.json`` pointing Python at it), runs the
simulator there and reads its output JSON (:func:`read_output`): tasks finished,
schedule and planner errors, entry timeouts, and the scheduler's own counts.

``lifelong``'s planner uses all of its time limit (``planTimeLimit``), so a run takes
about ``timesteps x plan_time_ms``, and its result depends on the machine's speed: the
official simulator is deterministic only up to timing.
"""

from __future__ import annotations

import dataclasses
import json
import os
import subprocess
import sys
import sysconfig
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from rtaw_marl.integrations.lorr.entry import SPEC_VARIABLE, RunSpec
from rtaw_marl.integrations.lorr.kit import KitBuild, StartKitError
from rtaw_marl.integrations.lorr.planner import PLANNER_SPEC_VARIABLE, PlannerSpec
from rtaw_marl.sim.lorr import read_problem

__all__ = ["RUN_FILES", "LoRRRun", "read_output", "run_lifelong"]

#: What :func:`run_lifelong` and ``lifelong`` write in a run folder (and nothing else).
RUN_FILES = frozenset(
    {"spec.json", "pyTaskScheduler.py", "pyMAPFPlanner.py", "config.json", "output.json",
     "lifelong.log", "stdout.txt", "stats.json", "__pycache__"}
)  # fmt: skip

#: The run folder's module, imported by ``lifelong``: the start kit's types, then ours.
_SHIM = '''"""Written by rtaw_marl: serves an rtaw_marl policy as LoRR's task scheduler."""
import site

site.addsitedir({site!r})
import MAPF  # noqa: F401,E402  (registers the start kit's types before ours get them)
from rtaw_marl.integrations.lorr.entry import pyTaskScheduler  # noqa: F401,E402
'''
#: The planner track's module: the own executor as LoRR's planner.
_PLANNER_SHIM = '''"""Written by rtaw_marl: serves the own PIBT executor as LoRR's planner."""
import site

site.addsitedir({site!r})
import MAPF  # noqa: F401,E402  (registers the start kit's types before ours get them)
from rtaw_marl.integrations.lorr.planner import pyMAPFPlanner  # noqa: F401,E402
'''


@dataclass(frozen=True)
class LoRRRun:
    """What one ``lifelong`` run reports.

    Attributes:
        policy: The scheduler's label.
        tasks_finished: ``numTaskFinished``.
        timesteps: The simulated timesteps.
        team_size: Robots.
        schedule_errors: ``numScheduleErrors`` (invalid schedules, refused by LoRR).
        planner_errors: ``numPlannerErrors`` (invalid moves).
        timeouts: ``numEntryTimeouts`` (timesteps the entry ran past its limit).
        wall_s: Seconds the run took.
        scheduler: The scheduler's counts (decisions, deferred robots, seconds), empty
            for LoRR's own scheduler.
        output: The output JSON.
    """

    policy: str
    tasks_finished: int
    timesteps: int
    team_size: int
    schedule_errors: int
    planner_errors: int
    timeouts: int
    wall_s: float
    output: str
    scheduler: dict[str, Any] = field(default_factory=dict)


def run_lifelong(
    build: KitBuild,
    problem: str | Path,
    folder: Path,
    spec: RunSpec | PlannerSpec | None,
    label: str,
    timesteps: int,
    plan_time_ms: int = 1000,
    preprocess_time_ms: int = 30000,
) -> LoRRRun:
    """Run ``lifelong`` on ``problem`` in ``folder`` (made here, must not exist).

    Args:
        build: The ``python`` build with a :class:`RunSpec`, ``planner`` with a
            :class:`PlannerSpec`, ``default`` without a spec.
        problem: The LoRR problem JSON.
        folder: The run folder.
        spec: The policy to serve as scheduler, the own executor to serve as planner, or
            ``None`` for the kit's own scheduler and planner.
        label: The scheduler's name in results.
        timesteps: ``simulationTime``.
        plan_time_ms: ``planTimeLimit`` per timestep (scheduler and planner together).
        preprocess_time_ms: ``preprocessTimeLimit``.

    Raises:
        StartKitError: The simulator failed or wrote no output; the scheduler raised.
        TaskFileError: ``problem`` is not a LoRR problem.
    """
    problem = read_problem(problem).path.resolve()
    wanted = {type(None): "default", RunSpec: "python", PlannerSpec: "planner"}[type(spec)]
    if build.variant != wanted:
        raise StartKitError(
            f"this run needs the start kit's {wanted} build, not {build.variant} (LoRR's own "
            "scheduler and planner: default; a policy: python; the own planner: planner)"
        )
    folder.mkdir(parents=True)
    env = dict(os.environ)
    if spec is not None:
        spec = dataclasses.replace(spec, problem=str(problem), stats=str(folder / "stats.json"))
        spec.write(folder / "spec.json")
        site = sysconfig.get_paths()["purelib"]
        module, shim, variable = (
            ("pyMAPFPlanner.py", _PLANNER_SHIM, PLANNER_SPEC_VARIABLE)
            if isinstance(spec, PlannerSpec)
            else ("pyTaskScheduler.py", _SHIM, SPEC_VARIABLE)
        )
        (folder / module).write_text(shim.format(site=site), encoding="utf-8")
        (folder / "config.json").write_text(json.dumps({"python_path": str(folder)}))
        env[variable] = str(folder / "spec.json")
        env["PYTHONPATH"] = os.pathsep.join([str(build.module_dir), str(folder)])
        env.setdefault("PYTHONHOME", sys.base_prefix)
    output = folder / "output.json"
    command = [
        str(build.lifelong), "-i", str(problem), "-o", str(output), "-s", str(int(timesteps)),
        "-t", str(int(plan_time_ms)), "-p", str(int(preprocess_time_ms)),
        "-l", str(folder / "lifelong.log"),
    ]  # fmt: skip
    start = time.perf_counter()
    with open(folder / "stdout.txt", "w", encoding="utf-8") as out:
        done = subprocess.run(command, cwd=folder, env=env, stdout=out, stderr=subprocess.STDOUT)
    wall = time.perf_counter() - start
    stats = _scheduler_stats(folder / "stats.json") if spec is not None else {}
    if stats.get("errors"):
        last = [ln for ln in str(stats["errors"][0]).splitlines() if ln.strip()][-1]
        part = "planner" if isinstance(spec, PlannerSpec) else "scheduler"
        raise StartKitError(f"{label}: the {part} failed inside lifelong: {last} ({folder})")
    if done.returncode != 0 or not output.is_file():
        raise StartKitError(
            f"{label}: lifelong exited {done.returncode}: {_last_line(folder)} ({folder})"
        )
    return read_output(output, label, wall_s=wall, scheduler=stats)


def read_output(
    path: str | Path, label: str, wall_s: float = float("nan"), scheduler: dict | None = None
) -> LoRRRun:
    """The counts of a ``lifelong`` output JSON.

    Raises:
        StartKitError: Not a LoRR 2024 output file.
    """
    path = Path(path)
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
        return LoRRRun(
            policy=label,
            tasks_finished=int(data["numTaskFinished"]),
            timesteps=_timesteps(data),
            team_size=int(data["teamSize"]),
            schedule_errors=int(data["numScheduleErrors"]),
            planner_errors=int(data["numPlannerErrors"]),
            timeouts=int(data["numEntryTimeouts"]),
            wall_s=float(wall_s),
            output=str(path),
            scheduler=dict(scheduler or {}),
        )
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise StartKitError(f"{path}: not a LoRR output file ({exc})") from None


def _timesteps(data: dict[str, Any]) -> int:
    """The simulated timesteps: one action per timestep in each actual path."""
    paths = data.get("actualPaths")
    if paths and paths[0]:
        return len(str(paths[0]).split(","))
    return int(data["makespan"])


def _scheduler_stats(path: Path) -> dict[str, Any]:
    if not path.is_file():
        return {}
    return json.loads(path.read_text(encoding="utf-8"))


def _last_line(folder: Path) -> str:
    for name in ("stdout.txt", "lifelong.log"):
        file = folder / name
        if file.is_file():
            lines = [ln for ln in file.read_text(errors="replace").splitlines() if ln.strip()]
            fatal = [ln for ln in lines if "rror" in ln or "fatal" in ln.lower()]
            if fatal or lines:
                return (fatal or lines)[-1].strip()[:200]
    return "no output"
