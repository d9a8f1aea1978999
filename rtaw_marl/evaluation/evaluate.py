"""Run policies on seeded episodes of the simulator and collect their metrics."""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping, Sequence
from typing import Protocol

from rtaw_marl.errors import ScheduleError
from rtaw_marl.evaluation.journal import EpisodeJournal
from rtaw_marl.sim.core import WarehouseSim
from rtaw_marl.sim.inputs import seed_list
from rtaw_marl.sim.mapf.conflicts import check_schedule
from rtaw_marl.sim.metrics import EpisodeMetrics

__all__ = [
    "WARM_UP_DECISIONS",
    "SimPolicy",
    "TimeEstimate",
    "duration",
    "evaluate",
    "run_episode",
    "warm_up",
]

_PROGRESS_EVERY = 256

#: Untimed decisions each policy plays before its first timed episode. One decision
#: already loads the compiled kernels (numba, the first torch call); a few more reach
#: the executor's completion events too. Measured: without it the first policy's first
#: episode took 0.30 s against 0.004 s for the next (10 robots, 100 tasks).
WARM_UP_DECISIONS = 16


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


def warm_up(sim: WarehouseSim, policy: SimPolicy, seed: int, decisions: int) -> int:
    """Play up to ``decisions`` decisions of ``policy`` from ``seed``, untimed and
    unrecorded, so that one-time costs (compilation, loading) are paid before timing.

    The next episode resets the simulator and the policy, so its outcome is unchanged.

    Returns:
        The number of decisions played (none, without a reset, when ``decisions`` is 0).
    """
    if decisions <= 0:
        return 0
    sim.reset(seed)
    policy.reset(seed)
    played = 0
    while played < decisions and not sim.done:
        sim.step(policy.act_sim(sim))
        played += 1
    return played


def evaluate(
    sim: WarehouseSim,
    policies: Mapping[str, SimPolicy],
    seeds: Sequence[int],
    on_decisions: Callable[[int], None] | None = None,
    journal: EpisodeJournal | None = None,
    on_seed: Callable[[int, int], None] | None = None,
    warm_up_decisions: int = WARM_UP_DECISIONS,
) -> dict[str, dict[str, list[float]]]:
    """Evaluate every policy on every seed.

    Seed by seed, every policy on each: the episodes run so far then sample every
    policy's cost alike, so a time estimate from the first seeds holds for the rest.

    Args:
        sim: The simulator.
        policies: Policies by name.
        seeds: Episode seeds (distinct).
        on_decisions: Progress callback (see :func:`run_episode`) for the episodes that
            run; episodes replayed from the journal are not counted.
        journal: Where each finished episode is recorded as it finishes; episodes it
            already holds (a resumed evaluation) are taken from it instead of run.
        on_seed: Called after each seed with episodes to run, once they have run, with
            the number of such seeds done and their total (drives :class:`TimeEstimate`).
        warm_up_decisions: Before its first episode that runs, each policy plays this
            many untimed decisions (:func:`warm_up`), so that no policy's
            ``wall_time_s`` pays for compilation because it happened to run first.

    Returns:
        ``{policy: {metric: [one value per seed]}}`` with every :class:`EpisodeMetrics`
        field plus ``wall_time_s`` (seconds per episode, warm-up excluded); with a
        collision-aware navigator also the executor's ``planning_calls``,
        ``evacuations`` (robots moved out of another's way) and ``cbs_fallbacks`` per
        episode.

    Raises:
        ConfigError: A seed is not an integer >= 0 or is given twice.
        ScheduleError: A collision-aware episode's executed schedule breaks a rule
            (a conflict, an illegal move, a task not served).
    """
    seeds = seed_list(seeds)
    results: dict[str, dict[str, list[float]]] = {name: {} for name in policies}
    todo = [s for s in seeds if any(_journalled(journal, n, s) is None for n in policies)]
    done = 0
    warmed: set[str] = set()
    for seed in seeds:
        for name, policy in policies.items():
            row = _journalled(journal, name, seed)
            if row is None:
                if name not in warmed:
                    warmed.add(name)
                    warm_up(sim, policy, seed, warm_up_decisions)
                row = _episode(sim, policy, seed, on_decisions)
                if journal is not None:
                    journal.record(name, seed, row)
            for key, value in row.items():
                results[name].setdefault(key, []).append(value)
        if done < len(todo) and todo[done] == seed:
            done += 1
            if on_seed is not None:
                on_seed(done, len(todo))
    return results


def _journalled(journal: EpisodeJournal | None, policy: str, seed: int) -> dict[str, float] | None:
    return None if journal is None else journal.get(policy, seed)


def _episode(
    sim: WarehouseSim, policy: SimPolicy, seed: int, on_decisions: Callable[[int], None] | None
) -> dict[str, float]:
    """One episode's metrics, its wall time and (collision-aware) executor statistics."""
    start = time.perf_counter()
    metrics = run_episode(sim, policy, seed, on_decisions)
    row = {**metrics.as_dict(), "wall_time_s": time.perf_counter() - start}
    if sim.executor.keeps_schedule:
        # Every collision-aware episode is validated on the checker's own code path,
        # unless it kept no positions (pibt's navigator.record=false, for fleets whose
        # trace would not fit in memory): its executor keeps robots on distinct cells.
        schedule = sim.schedule()
        if sim.config.episode_mode == "horizon":
            # Tasks in progress at the horizon are served but not in PIBT's schedule.
            check_schedule(sim.layout, schedule)
            if len(schedule.task_delivered) < metrics.tasks_finished:
                raise ScheduleError(
                    f"{metrics.tasks_finished} tasks finished by the horizon, the schedule "
                    f"delivers {len(schedule.task_delivered)}"
                )
        else:
            check_schedule(sim.layout, schedule, expected_tasks=metrics.tasks_served)
    row.update(sim.executor.stats())
    return row


class TimeEstimate:
    """The time an evaluation will take, from its first seeds (an ``on_seed`` callback
    of :func:`evaluate`).

    The first seed's episodes pay for warm-up (compilation, caches), so once two seeds
    are done the rate is that of the seeds after the first; a first seed that alone
    took over :attr:`WARM_UP_S` is long enough to estimate from. The estimate is
    announced once, in one line, when the whole run is to take over :attr:`LONG_S`;
    every later seed refreshes ``show`` (the progress bar's postfix).

    Args:
        announce: Receives the one ``estimated time: ...`` line (``print``).
        show: Receives the time left after each seed (e.g. ``bar.set_postfix_str``).
        clock: Seconds, monotonic.
    """

    LONG_S = 60.0
    WARM_UP_S = 10.0

    def __init__(
        self,
        announce: Callable[[str], None] = print,
        show: Callable[[str], None] | None = None,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self.announce, self.show, self.clock = announce, show, clock
        self.start = clock()
        self.first: float | None = None  # when the first seed was done
        self.announced = False

    def __call__(self, done: int, total: int) -> None:
        """Seed ``done`` of ``total`` (those with episodes to run) has finished."""
        now = self.clock()
        if done == 1:
            self.first = now
        if done >= 2 and self.first is not None:
            per_seed = (now - self.first) / (done - 1)
        elif now - self.start >= self.WARM_UP_S:
            per_seed = (now - self.start) / done
        else:
            return
        left = per_seed * (total - done)
        if self.show is not None:
            self.show(f"~{duration(left)} left")
        whole = now - self.start + left
        if not self.announced and whole > self.LONG_S:
            self.announced = True
            self.announce(
                f"estimated time: {duration(whole)} in all, {duration(left)} left "
                f"({per_seed:.3g} s per seed, {total} seeds to run)"
            )


def duration(seconds: float) -> str:
    """``42 s``, ``12.5 min``, ``3.2 h``, ``2.1 days``."""
    if seconds < 90:
        return f"{seconds:.0f} s"
    if seconds < 90 * 60:
        return f"{seconds / 60:.1f} min"
    if seconds < 48 * 3600:
        return f"{seconds / 3600:.1f} h"
    return f"{seconds / 86400:.1f} days"
