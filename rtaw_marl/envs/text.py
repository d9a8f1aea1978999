"""Text rendering of a simulator state (``render_mode="ansi"``)."""

from __future__ import annotations

import numpy as np

from rtaw_marl.sim.core import WarehouseSim

__all__ = ["render_ansi"]

#: Characters drawn per cell, later entries drawn over earlier ones.
LEGEND = {
    ".": "free",
    "@": "obstacle",
    "d": "destination of a queued task",
    "o": "origin of a queued task",
    "R": "robot (at the cell where it will next be free)",
    "*": "the robot choosing now",
}


def render_ansi(sim: WarehouseSim) -> str:
    """The grid with queued tasks and robots, plus a status line.

    Args:
        sim: A simulator after ``reset``.

    Returns:
        ``H`` lines of ``W`` characters (see :data:`LEGEND`) and one status line.
    """
    grid = np.where(sim.layout.obstacles, "@", ".").astype("<U1")
    queued = sim.tasks[sim.queue_ids[sim.queue_mask]]
    grid[queued[:, 3], queued[:, 2]] = "d"
    grid[queued[:, 1], queued[:, 0]] = "o"
    grid[sim.robot_xy[:, 1], sim.robot_xy[:, 0]] = "R"
    if not sim.done:
        x, y = sim.robot_xy[sim.robot]
        grid[y, x] = "*"
    lines = ["".join(row) for row in grid]
    status = (
        f"t={sim.time:.2f} decision {sim.decisions}/{sim.config.num_tasks} "
        f"robot {sim.robot} queued {int(sim.queue_mask.sum())}/{sim.queue_len}"
    )
    return "\n".join([*lines, status])
