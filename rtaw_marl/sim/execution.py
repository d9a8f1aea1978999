"""Execution strategies: how assigned robots travel and when they are free again.

:class:`~rtaw_marl.sim.core.WarehouseSim` decides *which* robot acts and *which* task
it takes; an :class:`Executor` decides what happens next: when the robot reaches the
task's origin (its TTD) and destination, when every robot is free, and which robot is
selected at the next decision. One executor belongs to one simulator: it is bound to
it at construction and reset with every episode.

:class:`InstantTravel` (``name="instant"``)
    Robots move independently (they pass through each other): a task's TTD is the
    distance model's distance to its origin and the robot is free at the completion time
    plus Gaussian noise ``N(noise_mean, noise_var)``, never before the decision time.
Collision-aware executors (``sipp``, ``cbs``)
    Robots occupy cells and wait for each other on a shared grid; see
    :mod:`rtaw_marl.sim.mapf.executors`.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol

import numpy as np

from rtaw_marl.errors import ConfigError
from rtaw_marl.sim.distances import DistanceModel
from rtaw_marl.sim.layout import Layout

if TYPE_CHECKING:
    # Type-only: the schedule type lives with the planners that produce it.
    from rtaw_marl.sim.mapf.schedule import Schedule

__all__ = ["EpisodeRecords", "Executor", "InstantTravel", "SimSettings", "check_whole_seconds"]


class SimSettings(Protocol):
    """The simulator settings an executor reads (a :class:`~rtaw_marl.sim.config.SimConfig`).

    A protocol rather than the class itself, so that this module does not import the
    simulator that imports it.
    """

    @property
    def num_robots(self) -> int: ...
    @property
    def num_tasks(self) -> int: ...
    @property
    def noise_mean(self) -> float: ...
    @property
    def noise_var(self) -> float: ...
    @property
    def robot_free_times(self) -> Sequence[float] | None: ...
    @property
    def episode_mode(self) -> str: ...
    @property
    def horizon(self) -> int | None: ...


@dataclass(frozen=True)
class EpisodeRecords:
    """The simulator's per-episode arrays an executor reads and keeps current.

    The arrays are the simulator's own (views, not copies), allocated at each reset.
    ``T`` is the number of tasks of the episode, ``M`` the number of robots.

    Attributes:
        tasks: ``int64 [T, 4]`` every task ``(ox, oy, dx, dy)`` in arrival order.
        task_arrival: ``float64 [T]`` time each task entered the queue.
        task_assigned: ``float64 [T]`` decision time at which it was assigned.
        task_ttd: ``float64 [T]`` its travel delay (executed once the episode is done).
        task_finished: ``float64 [T]`` its completion time.
        task_robot: ``int64 [T]`` the robot that took it, ``-1`` if none.
        robot_busy: ``float64 [M]`` time each robot spent on tasks.
        robot_free_at: ``float64 [M]`` time each robot is free, as the policy observes
            it; the executor updates it in place.
    """

    tasks: np.ndarray
    task_arrival: np.ndarray
    task_assigned: np.ndarray
    task_ttd: np.ndarray
    task_finished: np.ndarray
    task_robot: np.ndarray
    robot_busy: np.ndarray
    robot_free_at: np.ndarray


class Executor(ABC):
    """How the robots of one simulator travel, and when each is free."""

    #: Short name for reports: ``"instant"``, ``"sipp"``, ``"cbs"``.
    name: str = ""

    @property
    @abstractmethod
    def collision_aware(self) -> bool:
        """Whether robots occupy cells and wait for each other (a schedule exists)."""

    @property
    def keeps_schedule(self) -> bool:
        """Whether :meth:`schedule` can give the episode's executed schedule (a
        collision-aware executor told not to record positions cannot)."""
        return self.collision_aware

    @abstractmethod
    def bind(self, config: SimSettings, layout: Layout, distance_model: DistanceModel) -> None:
        """Attach to a simulator; called once by its constructor.

        Raises:
            ConfigError: The simulator's settings do not suit this executor.
        """

    @abstractmethod
    def reset(self, starts: np.ndarray, records: EpisodeRecords, rng: np.random.Generator) -> None:
        """Start an episode.

        Args:
            starts: ``int64 [M, 2]`` start cell ``(x, y)`` per robot.
            records: The episode's arrays; ``robot_free_at`` holds the first free times.
            rng: The episode's noise generator (the same for every policy).
        """

    @abstractmethod
    def assign(
        self,
        robot: int,
        now: float,
        task: int,
        row: np.ndarray,
        distance: float,
        length: float,
    ) -> tuple[float, float]:
        """Send ``robot`` (free at ``now``) on ``task`` and update ``robot_free_at``.

        Args:
            robot: The selected robot.
            now: The decision time.
            task: Task id (row of ``records.tasks``).
            row: ``int64 [4]`` the task ``(ox, oy, dx, dy)``.
            distance: DistanceModel distance from the robot to the origin.
            length: DistanceModel distance from the origin to the destination.

        Returns:
            ``(ttd, finish)``: the task's travel delay and completion time as known now.
        """

    @abstractmethod
    def next_robot(self, now: float) -> tuple[int, float]:
        """The robot that becomes free next (ties: lowest id) and when.

        Args:
            now: The current decision time (0 at reset).

        Raises:
            PlanningError: No robot can ever become free (collision-aware executors).
        """

    def free_robots(self, now: float) -> np.ndarray | None:
        """The robots free at ``now`` besides the one just selected, if the executor
        knows them better than the planned free times (``None``: robots whose planned
        free time is ``<= now``)."""
        del now
        return None

    @abstractmethod
    def finish(self, now: float) -> None:
        """The last decision was taken at ``now``: complete every assigned task and write
        the executed times into the records."""

    def finish_at(self, horizon: int) -> None:
        """A fixed-horizon episode ends at ``horizon`` (``episode_mode=horizon``): by
        default every assigned task is still completed (:meth:`finish`); the metrics
        count the tasks finished by the horizon."""
        self.finish(horizon)

    @abstractmethod
    def schedule(self) -> Schedule:
        """The executed episode (every robot's cell at every second).

        Raises:
            ConfigError: Robots move independently: there is no schedule.
        """

    #: Whether :meth:`release`, :meth:`started` and :meth:`defer` exist (``sim.reassign``
    #: and the per-timestep budgets need them).
    releases: bool = False

    def release(self, robot: int, now: float) -> np.ndarray:
        """Take ``robot``'s task away before it reaches the pickup: the robot is free at
        ``now`` where it stands (LoRR's reassignment).

        Returns:
            ``int64 [2]`` the robot's cell ``(x, y)``.

        Raises:
            ConfigError: This executor cannot release robots (:attr:`releases`).
        """
        del robot, now
        raise ConfigError(f"the {self.name!r} executor cannot take a task from its robot")

    def started(self, tasks: np.ndarray) -> np.ndarray:
        """``bool [K]``: whether each of ``tasks`` (assigned ids) was picked up.

        Raises:
            ConfigError: This executor cannot tell (:attr:`releases`).
        """
        del tasks
        raise ConfigError(f"the {self.name!r} executor does not report pickups as they happen")

    def defer(self) -> None:
        """The robots free now wait for the next timestep (the policy's budget for this
        one is spent; ``sim.decision_budget``, ``sim.time_budget_ms``).

        Raises:
            ConfigError: This executor has no timesteps to defer to (:attr:`releases`).
        """
        raise ConfigError(f"the {self.name!r} executor has no timesteps to defer robots to")

    def stats(self) -> dict[str, float]:
        """Counters of the episode (none by default)."""
        return {}

    def travel_noise(self) -> np.ndarray | None:
        """The completion noise per decision, for rollouts; ``None`` when travel is not
        modelled by noise (collision-aware executors)."""
        return None

    def load_travel(self, noise: np.ndarray, decisions: int, free_at: np.ndarray) -> None:
        """Continue an episode from a snapshot (:meth:`WarehouseSim.load_state`).

        Raises:
            ConfigError: This executor cannot be restored (it is collision-aware).
        """
        raise ConfigError(f"a {self.name!r} executor cannot load a simulator state")


class InstantTravel(Executor):
    """Independent robots timed by the distance model's distances plus completion noise."""

    name = "instant"

    @property
    def collision_aware(self) -> bool:
        return False

    def bind(self, config: SimSettings, layout: Layout, distance_model: DistanceModel) -> None:
        del layout
        self._config = config
        self._noise_std = float(np.sqrt(config.noise_var))
        self._navigator_name = distance_model.name

    def reset(self, starts: np.ndarray, records: EpisodeRecords, rng: np.random.Generator) -> None:
        del starts
        cfg = self._config
        # One draw per decision, made up front: every policy gets the same noise.
        if self._noise_std > 0:
            self._noise = rng.normal(cfg.noise_mean, self._noise_std, size=cfg.num_tasks)
        else:
            self._noise = np.full(cfg.num_tasks, float(cfg.noise_mean))
        self._decisions = 0
        self._free_at = records.robot_free_at

    def assign(
        self,
        robot: int,
        now: float,
        task: int,
        row: np.ndarray,
        distance: float,
        length: float,
    ) -> tuple[float, float]:
        del task, row
        finish = now + distance + length + float(self._noise[self._decisions])
        if finish < now:
            finish = now
        self._decisions += 1
        self._free_at[robot] = finish
        return distance, finish

    def travel_noise(self) -> np.ndarray:
        return self._noise.copy()

    def load_travel(self, noise: np.ndarray, decisions: int, free_at: np.ndarray) -> None:
        self._noise = noise
        self._decisions = decisions
        self._free_at = free_at

    def next_robot(self, now: float) -> tuple[int, float]:
        del now
        robot = int(self._free_at.argmin())
        return robot, float(self._free_at[robot])

    def finish(self, now: float) -> None:
        del now  # times are final as assigned

    def schedule(self) -> Schedule:
        raise ConfigError(
            f"navigator {self._navigator_name!r} moves robots independently and has no "
            "schedule; use navigator=sipp or navigator=cbs"
        )


def check_whole_seconds(config: SimSettings, name: str) -> None:
    """Collision-aware executors plan in whole seconds: no completion noise, integer starts.

    Raises:
        ConfigError: The noise is not zero or a first free time is fractional.
    """
    if config.noise_mean != 0 or config.noise_var != 0:
        raise ConfigError(
            f"navigator {name!r} plans paths in whole seconds and times tasks by them: "
            f"set sim.noise_mean=0 sim.noise_var=0 (got {config.noise_mean}, {config.noise_var})"
        )
    times = config.robot_free_times or ()
    if any(t != int(t) for t in times):
        raise ConfigError(
            f"navigator {name!r} needs whole-second sim.robot_free_times, got {list(times)}"
        )
