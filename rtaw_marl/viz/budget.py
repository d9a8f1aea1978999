"""What a viewer page will cost, estimated before the work starts (``rtaw-view``).

A page of ``M`` robots over ``T`` timesteps holds every robot's move at every timestep,
and making it holds more: the simulator's record of every cell, the schedule, the
conflict checker's sorted copies, the packing's temporaries. Memory grows with
``M x T``: 8.3 GB at 10,000 robots and 5,000 timesteps (docs/performance.md), so a run
three times that size does not fit a 24 GB machine and would be killed, or swap for
hours, after minutes of playing. :func:`check_cost` prints the estimate of a big run
and refuses one that cannot fit in the memory available now, naming what to lower.

The constants were measured with ``/usr/bin/time -v`` (peak resident memory) on
``rtaw-view scenario=lorr tasks.problem=warehouse_large_5000.json tasks.starts=random
policy=mpdm`` (PIBT, LoRR's 500 x 140 map) at six sizes: ``M x T`` = 4,000 x 1,000,
4,000 x 2,000, 8,000 x 2,000, 10,000 x 2,000, 10,000 x 4,000 and 20,000 x 1,000 (3.1 to
7.5 GB), fitted as ``fixed + per robot x M + per robot-timestep x M x T`` (residuals
within 0.16 GB). The constants below give 8.4 GB at 10,000 x 5,000 (the interpreter's
0.23 GB aside, already resident when they are used), where the docs measured 8.3 GB.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable
from dataclasses import dataclass

from rtaw_marl.errors import ConfigError

__all__ = [
    "ViewCost",
    "available_memory",
    "check_cost",
    "duration",
    "gigabytes",
    "play_cost",
    "saved_cost",
]

#: Bytes per robot-timestep of one played episode: its slope in the fit above (106 B:
#: the simulator's record, the schedule's int64 cells, the checker's sorted copies, the
#: move codes and the tasks, which also grow with M x T in a horizon episode).
PER_ROBOT_STEP = 106
#: Bytes per robot-timestep of each further episode shown side by side: its schedule
#: (int64 cells, 16 B) is kept while the next one is played. Measured: policy=[mpdm,
#: batch] at 4,000 x 2,000 peaked 131 MB (16.4 B per robot-timestep) above mpdm alone.
PER_ROBOT_STEP_KEPT = 16
#: Bytes per robot: the fleet's planner state (the fit's slope in M: 102 KB).
PER_ROBOT = 100_000
#: Bytes that grow with neither: the fit's intercept (2.33 GB) less the interpreter
#: and libraries (0.23 GB, ``rtaw-view layout=A``), already resident when the estimate
#: is made. Mostly distance-field caches, which fill up only on a large map: scaled
#: below by the map's cells, up to the 70,000 of warehouse_large where it was measured.
FIXED = 2_100_000_000
FIXED_CELLS = 70_000
#: Seconds per robot-timestep of a played episode (play, check, pack, write), and per
#: robot: the fit of the same runs' wall times (26 s at 4,000 x 2,000, 114 s at
#: 10,000 x 4,000, on the 2-core machine with other jobs running).
SECONDS_PER_ROBOT_STEP = 2.5e-6
SECONDS_PER_ROBOT = 1.5e-3
#: Bytes and seconds per robot-timestep of a saved episode (``schedule=``): no
#: simulator, but the file's text, its parsed actions and their int64 sums. Measured
#: the same way on ``rtaw-view schedule=`` of ``rtaw-render``'s LoRR output of
#: warehouse_large, 4,000 and 8,000 robots x 2,000 timesteps (34 and 69 MB files):
#: peaks 1.51 and 2.63 GB (140 B per robot-timestep between them), 12.9 s and 27.5 s.
SAVED_PER_ROBOT_STEP = 140
SAVED_SECONDS_PER_ROBOT_STEP = 1.8e-6
#: A run whose estimate reaches either is announced before it starts.
SHOWN_BYTES = 2**30
SHOWN_SECONDS = 60.0


@dataclass(frozen=True)
class ViewCost:
    """The estimated cost of one page.

    Attributes:
        robots: ``M``.
        timesteps: ``T`` (an estimate itself for an episode that runs until its tasks
            are done).
        episodes: Episodes side by side (1 or 2).
        nbytes: Peak memory, bytes.
        seconds: Wall time on a machine like the one measured.
    """

    robots: int
    timesteps: int
    episodes: int
    nbytes: int
    seconds: float

    def size(self) -> str:
        """``"30,000 robots x 5,000 timesteps x 2 episodes"``."""
        shown = f"{self.robots:,} robots x {self.timesteps:,} timesteps"
        return shown + (f" x {self.episodes} episodes" if self.episodes > 1 else "")


def play_cost(robots: int, timesteps: int, episodes: int, cells: int) -> ViewCost:
    """The cost of playing ``episodes`` of ``robots`` for ``timesteps`` on a map of
    ``cells`` cells, then making their page."""
    steps = robots * timesteps
    nbytes = (
        round(FIXED * min(1.0, cells / FIXED_CELLS))
        + PER_ROBOT * robots
        + steps * (PER_ROBOT_STEP + PER_ROBOT_STEP_KEPT * (episodes - 1))
    )
    seconds = episodes * (steps * SECONDS_PER_ROBOT_STEP + robots * SECONDS_PER_ROBOT)
    return ViewCost(robots, timesteps, episodes, nbytes, seconds)


def saved_cost(robots: int, timesteps: int, episodes: int) -> ViewCost:
    """The cost of showing ``episodes`` saved files of ``robots`` over ``timesteps``:
    no simulator, but each file's cells and moves as a played episode's."""
    steps = robots * timesteps
    nbytes = steps * (SAVED_PER_ROBOT_STEP + PER_ROBOT_STEP_KEPT * (episodes - 1))
    seconds = episodes * steps * SAVED_SECONDS_PER_ROBOT_STEP
    return ViewCost(robots, timesteps, episodes, nbytes, seconds)


def available_memory() -> int | None:
    """Bytes of memory available to a new allocation now (``MemAvailable`` of
    ``/proc/meminfo``: free memory plus caches the kernel can drop), else the free
    pages ``os.sysconf`` reports; ``None`` when the system says neither."""
    try:
        with open("/proc/meminfo", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024  # the file counts kB
    except (OSError, ValueError, IndexError):
        pass
    try:
        return int(os.sysconf("SC_AVPHYS_PAGES")) * int(os.sysconf("SC_PAGE_SIZE"))
    except (AttributeError, OSError, ValueError):
        return None


def check_cost(cost: ViewCost, lower: str, note: Callable[[str], None]) -> None:
    """Announce a big run's estimate; refuse one that cannot fit in memory.

    Args:
        cost: The estimate.
        lower: What to change, for the refusal (``"lower sim.horizon (now 5000) ..."``).
        note: Where the announcement goes (a progress line).

    Raises:
        ConfigError: The estimate exceeds the memory available now.
    """
    available = available_memory()
    if available is not None and cost.nbytes > available:
        raise ConfigError(
            f"{cost.size()} needs about {gigabytes(cost.nbytes)} of memory, more than the "
            f"{gigabytes(available)} available on this machine; {lower}"
        )
    if cost.nbytes >= SHOWN_BYTES or cost.seconds >= SHOWN_SECONDS:
        room = "" if available is None else f" ({gigabytes(available)} available)"
        note(
            f"estimate: {cost.size()}: about {gigabytes(cost.nbytes)} of memory{room} and "
            f"{duration(cost.seconds)}"
        )


def gigabytes(nbytes: int) -> str:
    """``"23.7 GB"``; ``"0.4 GB"`` below one."""
    return f"{nbytes / 1e9:,.1f} GB"


def duration(seconds: float) -> str:
    """``"about 40 s"``, ``"about 13 min"``, ``"about 2.5 h"``."""
    if seconds < 90:
        return f"about {max(1, round(seconds))} s"
    if seconds < 5400:
        return f"about {math.ceil(seconds / 60)} min"
    return f"about {seconds / 3600:.1f} h"
