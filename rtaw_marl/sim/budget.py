"""An up-front memory estimate of one simulator, so that a size nothing could hold
(``sim.num_tasks=1000000000000``, a 100000x100000 grid) is refused with the number
before numpy tries to allocate it.

The estimate counts the arrays that grow with the settings, at the bytes each element
takes, plus headroom for the temporaries made while building them:

* the grid: per cell, the obstacle mask and its copies, the region labels, the free
  and main-region cell lists, the padded grid of the planners;
* the distance model (A*, SIPP, CBS): one ``int32`` distance field per queue slot and
  its cached twin, each over the padded grid; ``direct`` keeps only coordinates;
* the episode: per task its row, its times and records, the completion noise and the
  temporaries of drawing it; per slot and per robot a few rows.

It is a lower bound in spirit (Python objects, caches that fill later and the policy's
own arrays come on top), so only settings that cannot fit are refused: the limit is
the machine's physical memory.
"""

from __future__ import annotations

import os

from rtaw_marl.errors import ConfigError
from rtaw_marl.sim.config import SimConfig
from rtaw_marl.sim.distances import SLOT_FIELDS_BYTES

__all__ = ["check_memory", "estimate_bytes", "memory_limit"]

#: Bytes per grid cell: masks (3), labels and their temporary (8), free and main cell
#: lists (32), the padded planner grid (1), the generators' temporaries (20).
_PER_CELL = 64
#: Bytes per cell of each queue slot's distance field (int32) and its cached copy.
_PER_SLOT_CELL = 8
#: Bytes per task: its int64 row (32), seven float64/int64 records (56), noise (8),
#: and the temporaries of drawing and scoring an episode (160).
_PER_TASK = 256
#: Bytes per queue slot (row, length, id, mask, coordinates) and per robot.
_PER_SLOT = 80
#: Bytes per slot of a pool too large for dense fields: its cell and coordinates.
_PER_SLOT_XY = 24
_PER_ROBOT = 64

_GIB = 2**30


def estimate_bytes(sim: SimConfig, width: int, height: int, fields: bool) -> int:
    """Bytes one simulator of ``sim`` on a ``width x height`` grid needs at least.

    Args:
        sim: The simulator settings.
        width: Grid columns.
        height: Grid rows.
        fields: Whether the navigator keeps a distance field per queue slot (every
            navigator but ``direct``).
    """
    cells = width * height
    padded = (width + 2) * (height + 2)
    tasks = sim.num_tasks + (sim.queue_len if sim.episode_mode == "paper" else 0)
    total = cells * _PER_CELL + tasks * _PER_TASK
    # Beyond SLOT_FIELDS_BYTES the slots keep cells, not fields (GridDistance.target_slots).
    dense = fields and sim.queue_len * padded * 4 <= SLOT_FIELDS_BYTES
    total += sim.queue_len * (_PER_SLOT + (padded * _PER_SLOT_CELL if dense else _PER_SLOT_XY))
    return total + sim.num_robots * _PER_ROBOT


def memory_limit() -> int:
    """The machine's physical memory in bytes (64 GiB when the system does not say)."""
    try:
        return int(os.sysconf("SC_PAGE_SIZE")) * int(os.sysconf("SC_PHYS_PAGES"))
    except (AttributeError, OSError, ValueError):
        return 64 * _GIB


def check_memory(sim: SimConfig, width: int, height: int, fields: bool, layout: str) -> None:
    """Refuse settings whose simulator cannot fit in this machine's memory.

    Args:
        sim: The simulator settings.
        width: Grid columns.
        height: Grid rows.
        fields: Whether the navigator keeps a distance field per queue slot.
        layout: The layout's name, for the message.

    Raises:
        ConfigError: The estimate exceeds :func:`memory_limit`; the message gives both
            and the settings that drive it.
    """
    need, limit = estimate_bytes(sim, width, height, fields), memory_limit()
    if need <= limit:
        return
    raise ConfigError(
        f"this simulator needs ~{_size(need)} of memory (sim.num_tasks={sim.num_tasks}, "
        f"sim.queue_len={sim.queue_len}, layout {layout} {width}x{height}), more than this "
        f"machine's {_size(limit)}; lower sim.num_tasks, sim.queue_len or the layout size"
    )


def _size(nbytes: int) -> str:
    for unit, scale in (("PiB", 2**50), ("TiB", 2**40), ("GiB", _GIB)):
        if nbytes >= scale:
            return f"{nbytes / scale:,.1f} {unit}"
    return f"{nbytes / 2**20:,.1f} MiB"
