"""A decision point whose state comes from outside: another simulator drives the fleet.

LoRR's start kit (:mod:`rtaw_marl.integrations.lorr`) moves its robots itself and asks
a scheduler, every timestep, which queued task each free robot takes. Every policy here
acts on a :class:`~rtaw_marl.sim.core.WarehouseSim`; :func:`load_decisions` puts such a
simulator in that outside state, so that any policy (a rule or a learned network)
decides through the one interface, ``act_sim``, as in its own episodes.

The simulator continues from the state: :meth:`~rtaw_marl.sim.core.WarehouseSim.step`
gives the selected robot its task and selects the next free one (lowest id first), so
the robots free at ``time`` decide in turn; once the next robot is free only later, the
caller reads the choices and loads the next timestep's state. Nothing is refilled in
between: the outside simulator reveals tasks.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rtaw_marl.errors import ConfigError
from rtaw_marl.sim.core import SimState, WarehouseSim

__all__ = ["DecisionState", "load_decisions"]


@dataclass(frozen=True)
class DecisionState:
    """The fleet and the queue at one timestep, as the outside simulator reports them.

    Attributes:
        time: The timestep.
        robot_xy: ``int64 [M, 2]`` each robot's cell when next free: its cell if free,
            the delivery of its task if busy.
        robot_free_at: ``float64 [M]`` when each robot is free: ``time`` for the free
            ones, an estimate (``time`` + its remaining travel) for the busy ones.
        queue_rows: ``int64 [N, 4]`` ``(ox, oy, dx, dy)`` of the task in each queue slot
            (zeros where ``queue_mask`` is false).
        queue_mask: ``bool [N]`` the slots that hold an unassigned task.
        queue_length: ``float64 [N]`` each queued task's travel after its pickup.
        queue_arrival: ``float64 [N]`` when each queued task was revealed.
        heading_rows: ``int64 [H, 4]`` the tasks robots are on their way to pick up.
        heading_robot: ``int64 [H]`` the robot of each.
        heading_pickup_at: ``float64 [H]`` when it is expected at the pickup (> ``time``).
    """

    time: float
    robot_xy: np.ndarray
    robot_free_at: np.ndarray
    queue_rows: np.ndarray
    queue_mask: np.ndarray
    queue_length: np.ndarray
    queue_arrival: np.ndarray
    heading_rows: np.ndarray
    heading_robot: np.ndarray
    heading_pickup_at: np.ndarray


def load_decisions(sim: WarehouseSim, state: DecisionState) -> bool:
    """Put ``sim`` at ``state``'s decision point.

    The queued tasks are tasks ``0..N-1`` (slot ``i`` holds task ``i``), those on
    their way to pickup follow; the episode's records start from them.

    Args:
        sim: A simulator with instant travel, reset once, of ``M`` robots and a queue of
            ``N`` slots (:func:`~rtaw_marl.sim.core.WarehouseSim.load_state` rules).
        state: The outside state.

    Returns:
        Whether a robot is free at ``state.time`` with a task queued (a decision to make);
        if so it is selected (the lowest id).

    Raises:
        ConfigError: The arrays do not fit ``sim`` (robots, queue length).
    """
    m, n = sim.num_robots, sim.queue_len
    if state.robot_xy.shape != (m, 2) or state.robot_free_at.shape != (m,):
        raise ConfigError(f"the outside state has {len(state.robot_xy)} robots, the simulator {m}")
    if state.queue_rows.shape != (n, 4) or state.queue_mask.shape != (n,):
        raise ConfigError(f"the outside queue has {len(state.queue_rows)} slots, the simulator {n}")
    h = len(state.heading_rows)
    total = n + h
    tasks = np.concatenate([state.queue_rows, state.heading_rows.reshape(h, 4)]).astype(np.int64)
    assigned = np.full(total, np.nan)
    ttd = np.full(total, np.nan)
    robot_of = np.full(total, -1, dtype=np.int64)
    assigned[n:] = state.time
    ttd[n:] = state.heading_pickup_at - state.time
    robot_of[n:] = state.heading_robot
    length = np.full(total, np.nan)
    length[:n] = np.where(state.queue_mask, state.queue_length, np.nan)
    arrival = np.full(total, np.nan)
    arrival[:n] = np.where(state.queue_mask, state.queue_arrival, np.nan)
    free_at = np.maximum(np.asarray(state.robot_free_at, dtype=np.float64), state.time)
    free = np.flatnonzero(free_at <= state.time)
    arrays = {
        "tasks": tasks,
        "task_length": length,
        "robot_start_xy": state.robot_xy.astype(np.int64),
        "robot_busy": np.zeros(m),
        "task_arrival": arrival,
        "task_assigned": assigned,
        "task_ttd": ttd,
        "task_finished": np.full(total, np.nan),
        "task_robot": robot_of,
        "queue_ids": np.where(state.queue_mask, np.arange(n), -1).astype(np.int64),
        "robot_xy": state.robot_xy.astype(np.int64),
        "robot_free_at": free_at,
        "queue_mask": state.queue_mask.astype(bool),
        "queue_rows": np.where(state.queue_mask[:, None], state.queue_rows, 0).astype(np.int64),
        "queue_length": np.where(state.queue_mask, state.queue_length, 0.0),
        "_owed": np.zeros(m, dtype=bool),
    }
    decide = bool(len(free)) and bool(state.queue_mask.any())
    scalars = {
        "robot": int(free[0]) if len(free) else int(free_at.argmin()),
        "time": float(state.time),
        "decisions": 0,
        "done": not decide,
        "truncated": False,
        "last_ttd": 0.0,
        # Nothing left to reveal: the outside simulator reveals tasks.
        "_next_task": total,
    }
    sim.load_state(SimState(arrays, scalars, np.zeros(max(m, 1))))
    return decide
