"""Per-episode metrics computed from the simulator's per-task records."""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

__all__ = ["EpisodeMetrics", "compute_metrics"]


@dataclass(frozen=True)
class EpisodeMetrics:
    """Figures of one episode, all in seconds (robots move one cell per second).

    Attributes:
        ttd: Total travel delay, the summed empty travel from each robot to the
            origin of the task it was given.
        makespan: Time at which the last served task was completed (the robot's free
            time after it, completion noise included).
        task_length: Summed origin -> destination travel of the served tasks.
        idle_mean: Mean over robots of the time within ``[0, makespan]`` a robot had no
            task (before its first task and after its last).
        idle_max: Largest per-robot idle time.
        wait_mean: Mean over served tasks of the time from arrival in the queue to pickup.
        wait_max: Longest such wait (starvation shows here).
        tasks_served: Number of tasks assigned during the episode.
        decisions: Number of decisions taken.
        tasks_finished: Tasks delivered (by the horizon in ``horizon`` episodes, where
            the TTD of a task not yet picked up counts until the horizon; otherwise
            every served task).
    """

    ttd: float
    makespan: float
    task_length: float
    idle_mean: float
    idle_max: float
    wait_mean: float
    wait_max: float
    tasks_served: int
    decisions: int
    tasks_finished: int = 0

    def as_dict(self) -> dict[str, float | int]:
        """The metrics as a plain JSON-ready dict."""
        return asdict(self)


def compute_metrics(
    served: np.ndarray,
    ttd: np.ndarray,
    length: np.ndarray,
    arrival: np.ndarray,
    assigned: np.ndarray,
    finished: np.ndarray,
    robot_busy: np.ndarray,
    decisions: int,
    horizon: int | None = None,
) -> tuple[EpisodeMetrics, np.ndarray]:
    """Aggregate per-task records into :class:`EpisodeMetrics`.

    Args:
        served: ``bool [T]``, which tasks were assigned.
        ttd: ``float [T]`` empty travel of each task.
        length: ``float [T]`` origin -> destination travel.
        arrival: ``float [T]`` time each task entered the queue.
        assigned: ``float [T]`` decision time at which each task was assigned.
        finished: ``float [T]`` free time of the robot after each task.
        robot_busy: ``float [M]`` total time each robot spent on tasks, from assignment
            until it was free again.
        decisions: Number of decisions taken.
        horizon: The last timestep of a ``horizon`` episode, else ``None``.

    Returns:
        The metrics and the per-robot idle times ``float [M]``.
    """
    if not served.any():
        idle = np.zeros_like(robot_busy)
        return EpisodeMetrics(0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0, decisions), idle
    if horizon is not None:
        # Censored at the horizon: what happens after it is not part of the episode.
        ttd = np.where(served, np.minimum(ttd, horizon - assigned), ttd)
        done = served & (finished <= horizon)
    else:
        done = served
    makespan = float(finished[done].max()) if done.any() else 0.0
    idle = makespan - robot_busy
    if horizon is not None:
        makespan = float(horizon)
        idle = np.maximum(horizon - robot_busy, 0.0)
    wait = assigned[served] + ttd[served] - arrival[served]
    metrics = EpisodeMetrics(
        ttd=float(ttd[served].sum()),
        makespan=makespan,
        task_length=float(length[served].sum()),
        idle_mean=float(idle.mean()),
        idle_max=float(idle.max()),
        wait_mean=float(wait.mean()),
        wait_max=float(wait.max()),
        tasks_served=int(served.sum()),
        decisions=decisions,
        tasks_finished=int(done.sum()),
    )
    return metrics, idle
