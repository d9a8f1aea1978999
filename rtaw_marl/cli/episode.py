"""One executed episode for the commands that show it (``rtaw-render``, ``rtaw-view``):
played with progress on stderr, then checked by the independent conflict checker."""

from __future__ import annotations

import sys
import time

from tqdm import tqdm

from rtaw_marl.evaluation.evaluate import SimPolicy, run_episode
from rtaw_marl.evaluation.transcript import progress_shown
from rtaw_marl.sim.core import WarehouseSim
from rtaw_marl.sim.mapf.conflicts import check_schedule
from rtaw_marl.sim.mapf.schedule import Schedule
from rtaw_marl.sim.metrics import EpisodeMetrics

__all__ = ["Progress", "note", "play_checked"]


def note(text: str) -> None:
    """One progress line on stderr."""
    print(text, file=sys.stderr, flush=True)


class Progress:
    """A tqdm bar on a terminal; else a line on stderr at every tenth of the total, so
    that a log shows a long episode moving without a line per refresh."""

    def __init__(self, name: str, total: int, unit: str) -> None:
        self.name, self.total, self.unit, self.done, self.start = name, total, unit, 0, time.time()
        self.bar = (
            tqdm(total=total, desc=f"playing {name}", unit=unit, file=sys.stderr)
            if progress_shown(True)
            else None
        )

    def to(self, done: int) -> None:
        """Advance to ``done`` of the total."""
        done = min(done, self.total)
        if self.bar is not None:
            self.bar.update(done - self.bar.n)
        elif done * 10 // max(self.total, 1) > self.done * 10 // max(self.total, 1):
            note(
                f"playing {self.name}: {done}/{self.total} {self.unit}s "
                f"({time.time() - self.start:.0f} s)"
            )
        self.done = done

    def close(self) -> None:
        """End the bar."""
        if self.bar is not None:
            self.bar.close()


def play_checked(
    sim: WarehouseSim, name: str, policy: SimPolicy, seed: int
) -> tuple[EpisodeMetrics, Schedule]:
    """Play one episode (progress in timesteps for horizon episodes, else decisions),
    then check its schedule.

    Raises:
        ConfigError: The navigator is not collision-aware (no schedule).
        ScheduleError: The checker finds a conflict (a bug in an executor).
    """
    horizon = sim.config.horizon if sim.config.episode_mode == "horizon" else None
    total = horizon if horizon is not None else sim.config.num_tasks
    progress = Progress(name, total, "timestep" if horizon is not None else "decision")
    start = time.perf_counter()

    def advance(decisions: int) -> None:
        progress.to(int(sim.time) if horizon is not None else progress.done + decisions)

    metrics = run_episode(sim, policy, seed, on_decisions=advance)
    progress.to(total)
    progress.close()
    note(f"{name}: played in {time.perf_counter() - start:.1f} s; checking the schedule")
    schedule = sim.schedule()
    check_schedule(sim.layout, schedule, expected_tasks=len(schedule.tasks))
    return metrics, schedule
