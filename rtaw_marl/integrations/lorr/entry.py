"""The ``pyTaskScheduler`` class LoRR's ``lifelong`` loads, reading its run spec.

``lifelong`` (built for the scheduler track with Python) imports a module named
``pyTaskScheduler`` and calls ``pyTaskScheduler(env)``, ``initialize(limit_ms)`` and,
every timestep, ``plan(limit_ms)`` (a list of task ids, one per robot). The run folder's
``pyTaskScheduler.py`` (written by :func:`~rtaw_marl.integrations.lorr.kit.run_lifelong`)
imports this class; the run spec, a JSON file named by the ``RTAW_LORR_SPEC``
environment variable, says which policy to serve and where to write its counts.

A failure inside the scheduler is written to the stats file (``errors``) before it
propagates, since ``lifelong`` prints a cast error and goes on with an empty schedule.
"""

from __future__ import annotations

import json
import os
import sys
import time
import traceback
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from rtaw_marl.integrations.lorr.pair_scheduler import PairScheduler
from rtaw_marl.integrations.lorr.scheduler import PolicyScheduler, Timestep, stats_dict
from rtaw_marl.policies.pairs import PairGreedy
from rtaw_marl.sim.distances import GridDistance
from rtaw_marl.utils.atomic import atomic_write

__all__ = ["SPEC_VARIABLE", "RunSpec", "pyTaskScheduler"]

#: The environment variable naming the run spec.
SPEC_VARIABLE = "RTAW_LORR_SPEC"


@dataclass(frozen=True)
class RunSpec:
    """What one ``lifelong`` run serves.

    Attributes:
        problem: The LoRR problem JSON (the mirror simulator is built on its map).
        policy: A rule's name, ``checkpoint`` / ``pretrained`` / ``matched`` with ``source``, or a
            user policy ``module:Name`` (imported from ``search_path``).
        source: The checkpoint path or shipped name of a learned policy.
        candidates: ``candidates=K`` of a learned policy.
        baselines: The rules' parameters (``BaselinesConfig`` keys).
        share: The part of LoRR's time limit the scheduler may use per timestep (its
            default scheduler takes half).
        overflow: What robots not served in time do (``wait`` or ``nearest``).
        timesteps: LoRR's ``simulationTime``: the stats are written at the last one.
        stats: Where the scheduler writes its counts (JSON).
        seed: The policy's tie-breaking seed.
        search_path: The folder a user policy's module is imported from (the working
            directory of the command; LoRR's process runs elsewhere).
    """

    problem: str
    policy: str
    stats: str
    timesteps: int
    source: str | None = None
    candidates: int | None = None
    baselines: dict[str, Any] = field(default_factory=dict)
    share: float = 0.5
    overflow: str = "wait"
    seed: int = 0
    search_path: str | None = None

    def write(self, path: Path) -> None:
        atomic_write(path, lambda fh: fh.write(json.dumps(asdict(self), indent=1).encode()))

    @classmethod
    def read(cls, path: str | Path) -> RunSpec:
        return cls(**json.loads(Path(path).read_text(encoding="utf-8")))


def build_scheduler(spec: RunSpec) -> PolicyScheduler | PairScheduler:
    """The mirror simulator of ``spec.problem`` and the policy, ready to plan
    (``pair_greedy``: its whole-fleet version, which reschedules every timestep)."""
    from rtaw_marl.policies import BaselinesConfig, make_baseline
    from rtaw_marl.policies.user import import_policy, is_import_spec
    from rtaw_marl.scenarios.lorr import lorr_scenario
    from rtaw_marl.sim.builder import build_sim

    # Fields of a big map are big (280 KB on warehouse_large): a cache for thousands.
    scenario = lorr_scenario(spec.problem, navigator={"name": "astar", "cache_mb": 1024.0})
    m = int(scenario.sim["num_robots"])
    # Instant travel on the map; one decision per free robot and timestep at most, and
    # no horizon of its own: LoRR's simulator ends the episode.
    sim = build_sim(
        scenario.with_sim(
            num_tasks=m + int(scenario.sim["queue_len"]), horizon=10**9, reassign=False
        ).spec()
    )
    if spec.policy == PairGreedy.name:
        # Every open task's pickup field is read every timestep: a cache for the whole
        # window (a smaller one evicts and recomputes fields each timestep).
        window = int(scenario.sim["queue_len"])
        field_mb = (sim.layout.width + 2) * (sim.layout.height + 2) * 4 / 2**20
        model = GridDistance(sim.layout, cache_mb=max(1024.0, 1.25 * window * field_mb))
        first = np.asarray(getattr(sim.stream, "tasks", np.zeros((0, 4))))[:window, :2]
        return PairScheduler(sim.layout, model, first_pickups=first)
    if is_import_spec(spec.policy):
        if spec.search_path is not None and spec.search_path not in sys.path:
            sys.path.append(spec.search_path)
        _, user_policy = import_policy(spec.policy)
        return PolicyScheduler(user_policy, sim, seed=spec.seed, overflow=spec.overflow)
    if spec.policy in ("checkpoint", "pretrained", "matched"):
        from rtaw_marl.policies.network import load_policy

        policy: Any = load_policy(str(spec.source), candidates=spec.candidates)
        if spec.policy == "matched":
            from rtaw_marl.policies.matched import MatchedPolicy

            policy = MatchedPolicy(policy)
    else:
        policy = make_baseline(spec.policy, params=BaselinesConfig(**spec.baselines))
    return PolicyScheduler(policy, sim, seed=spec.seed, overflow=spec.overflow)


class pyTaskScheduler:
    """LoRR's Python task scheduler serving the policy of the run spec.

    Args:
        env: LoRR's ``SharedEnvironment`` (its pybind11 binding, module ``MAPF``).
    """

    def __init__(self, env: Any) -> None:
        self.env = env
        self.spec = RunSpec.read(os.environ[SPEC_VARIABLE])
        self.scheduler: PolicyScheduler | None = None

    def initialize(self, preprocess_time_limit: int) -> None:
        """Build the mirror and the policy, then load distance fields for the first tasks
        (LoRR's preprocessing stage; the kit's default scheduler takes half of it)."""
        start = time.perf_counter()
        try:
            self.scheduler = build_scheduler(self.spec)
            left = 0.5 * preprocess_time_limit / 1000.0 - (time.perf_counter() - start)
            self.scheduler.preload(left)
            layout = self.scheduler.layout
            grid = np.asarray(list(self.env.map), dtype=bool).reshape(self.env.rows, self.env.cols)
            if grid.shape != layout.obstacles.shape or not np.array_equal(grid, layout.obstacles):
                raise ValueError(f"LoRR's map is not the map of {self.spec.problem}")
        except BaseException:
            self._fail()
            raise

    def plan(self, time_limit: int) -> list[int]:
        """Every robot's task id (``-1``: none) for this timestep."""
        assert self.scheduler is not None, "initialize() was not called"
        env = self.env
        try:
            pool = env.task_pool
            step = Timestep(
                time=int(env.curr_timestep),
                locations=np.fromiter((s.location for s in env.curr_states), dtype=np.int64),
                schedule=np.asarray(list(env.curr_task_schedule), dtype=np.int64),
                pool=list(pool.keys()),
                read_task=lambda t: (list(pool[t].locations), int(pool[t].t_revealed)),
                progress=lambda t: int(pool[t].idx_next_loc),
            )
            elapsed = (env.plan_current_time() - env.plan_start_time).total_seconds()
            budget = self.spec.share * time_limit / 1000.0 - elapsed
            schedule = self.scheduler.plan(step, budget)
        except BaseException:
            self._fail()
            raise
        if step.time + 1 >= self.spec.timesteps or step.time % 100 == 0:
            self._write_stats()
        return schedule

    def _fail(self) -> None:
        if self.scheduler is not None:
            self.scheduler.stats.errors.append(traceback.format_exc(limit=4))
            self._write_stats()
        else:
            text = json.dumps({"errors": [traceback.format_exc(limit=4)]})
            atomic_write(Path(self.spec.stats), lambda fh: fh.write(text.encode()))

    def _write_stats(self) -> None:
        assert self.scheduler is not None
        text = json.dumps(stats_dict(self.scheduler.stats))
        atomic_write(Path(self.spec.stats), lambda fh: fh.write(text.encode()))
