"""Run policies on seeded episodes of the simulator and collect their metrics."""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping, Sequence
from typing import Protocol

from rtaw_marl.evaluation.journal import EpisodeJournal
from rtaw_marl.sim.core import WarehouseSim
from rtaw_marl.sim.mapf.conflicts import check_schedule
from rtaw_marl.sim.metrics import EpisodeMetrics

__all__ = ["SimPolicy", "evaluate", "run_episode"]

_PROGRESS_EVERY = 256


class SimPolicy(Protocol):
    """What evaluation needs of a :class:`rtaw_marl.policies.Policy`: its fast path on
    the simulator (every policy has it, the ``hindsight`` reference included)."""

    def reset(self, seed: int | None = None) -> None: ...

    def act_sim(self, sim: WarehouseSim) -> int: ...


def run_episode(
    sim: WarehouseSim,
    policy: SimPolicy,
    seed: int,
    on_decisions: Callable[[int], None] | None = None,
) -> EpisodeMetrics:
    """Play one episode of ``sim`` with ``policy`` from ``seed``.

    Args:
        sim: The simulator (reset here).
        policy: The policy (reset here with the same seed, for its tie-breaking).
        seed: Episode seed; the same seed gives every policy the same tasks and noise.
        on_decisions: Called with the number of decisions taken since the last call,
            every few hundred decisions (drives progress bars).

    Returns:
        The episode's metrics.
    """
    sim.reset(seed)
    policy.reset(seed)
    pending = 0
    while not sim.done:
        sim.step(policy.act_sim(sim))
        pending += 1
        if on_decisions is not None and pending == _PROGRESS_EVERY:
            on_decisions(pending)
            pending = 0
    if on_decisions is not None and pending:
        on_decisions(pending)
    return sim.metrics()


def evaluate(
    sim: WarehouseSim,
    policies: Mapping[str, SimPolicy],
    seeds: Sequence[int],
    on_decisions: Callable[[int], None] | None = None,
    journal: EpisodeJournal | None = None,
) -> dict[str, dict[str, list[float]]]:
    """Evaluate every policy on every seed.

    Args:
        sim: The simulator.
        policies: Policies by name.
        seeds: Episode seeds.
        on_decisions: Progress callback (see :func:`run_episode`); episodes replayed
            from the journal count all their decisions at once.
        journal: Where each finished episode is recorded as it finishes; episodes it
            already holds (a resumed evaluation) are taken from it instead of run.

    Returns:
        ``{policy: {metric: [one value per seed]}}`` with every :class:`EpisodeMetrics`
        field plus ``wall_time_s`` (seconds per episode); with a collision-aware
        navigator also the executor's ``planning_calls``, ``evacuations`` (robots moved
        out of another's way) and ``cbs_fallbacks`` per episode.

    Raises:
        ScheduleError: A collision-aware episode's executed schedule breaks a rule
            (a conflict, an illegal move, a task not served).
    """
    results: dict[str, dict[str, list[float]]] = {}
    for name, policy in policies.items():
        per_metric: dict[str, list[float]] = {}
        for seed in seeds:
            row = journal.get(name, int(seed)) if journal is not None else None
            if row is None:
                row = _episode(sim, policy, int(seed), on_decisions)
                if journal is not None:
                    journal.record(name, int(seed), row)
            elif on_decisions is not None:
                on_decisions(sim.config.num_tasks)
            for key, value in row.items():
                per_metric.setdefault(key, []).append(value)
        results[name] = per_metric
    return results


def _episode(
    sim: WarehouseSim, policy: SimPolicy, seed: int, on_decisions: Callable[[int], None] | None
) -> dict[str, float]:
    """One episode's metrics, its wall time and (collision-aware) executor statistics."""
    start = time.perf_counter()
    metrics = run_episode(sim, policy, seed, on_decisions)
    row = {**metrics.as_dict(), "wall_time_s": time.perf_counter() - start}
    if sim.executor.collision_aware:
        # Every collision-aware episode is validated on the checker's own code path.
        check_schedule(sim.layout, sim.schedule(), expected_tasks=metrics.tasks_served)
    row.update(sim.executor.stats())
    return row
