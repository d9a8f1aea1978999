"""The event-driven warehouse simulator: the paper's MDP without any RL framework.

State: ``M`` robots, each with the cell where it will be when free (the destination of
its current task, or its start) and the time it becomes free; a queue of ``N`` task
slots. At each decision the robot that becomes free next (ties: lowest robot id) is
*selected*; the policy picks one queued task for it. The robot travels to the task's
origin (this empty travel is the task's TTD) and on to its destination, then becomes
free at that completion time plus Gaussian noise (never earlier than the decision
time). The chosen slot is refilled from the task stream.

Episode modes (``episode_mode``):

``drain`` (default)
    Exactly ``num_tasks`` tasks are served. When the stream is exhausted, emptied
    slots stay empty (masked) until every task is assigned; the episode *terminates*.
``paper``
    As in the paper and its original code: ``num_tasks`` decisions with the queue
    always refilled, so tasks still queued at the end are never served; the episode is
    *truncated* (a time limit, not a terminal state).

Per decision the work is a handful of numpy calls over ``M`` robots and ``N`` slots.

How robots travel is the simulator's :class:`~rtaw_marl.sim.execution.Executor`:
:class:`~rtaw_marl.sim.execution.InstantTravel` (the default: distances plus noise) or a
collision-aware one (:class:`~rtaw_marl.sim.mapf.SIPPExecutor`,
:class:`~rtaw_marl.sim.mapf.CBSExecutor`) executing every task on the shared grid in
whole seconds: a task's TTD is the real arrival time at its origin minus the decision
time, waits included, and a robot is free when its planned path reaches the
destination. The reward of a decision is the TTD as known at that decision;
:meth:`WarehouseSim.metrics` reports the executed times, final once the episode is
done. :meth:`WarehouseSim.schedule` returns the executed episode.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from rtaw_marl.errors import ConfigError, InvalidActionError
from rtaw_marl.sim.clock import DecisionClock
from rtaw_marl.sim.config import PAIR_WEIGHT, REWARDS, SimBuffers, SimConfig
from rtaw_marl.sim.distances import DistanceModel
from rtaw_marl.sim.execution import EpisodeRecords, Executor, InstantTravel
from rtaw_marl.sim.inputs import slot_index
from rtaw_marl.sim.layout import Layout
from rtaw_marl.sim.metrics import EpisodeMetrics, compute_metrics
from rtaw_marl.sim.queue_distances import QueueDistances
from rtaw_marl.sim.reassign import Reassignment
from rtaw_marl.sim.tasks import TaskStream

if TYPE_CHECKING:
    # Type-only: the schedule type lives with the planners that produce it.
    from rtaw_marl.sim.mapf.schedule import Schedule

__all__ = ["SimState", "WarehouseSim"]

#: What an episode changes, in a :class:`SimState`: arrays, then scalars.
_STATE_ARRAYS = (
    "tasks", "task_length", "robot_start_xy", "robot_busy", "task_arrival", "task_assigned",
    "task_ttd", "task_finished", "task_robot", "queue_ids", "robot_xy", "robot_free_at",
    "queue_mask", "queue_rows", "queue_length", "_owed", "queue_holder", "task_moved",
)  # fmt: skip
_STATE_SCALARS = (
    "robot", "time", "decisions", "_retaken", "done", "truncated", "last_ttd", "_next_task",
)  # fmt: skip


@dataclass(frozen=True)
class SimState:
    """A snapshot of an episode (:meth:`WarehouseSim.state`).

    Attributes:
        arrays: Copies of the episode's arrays by attribute name.
        scalars: The selected robot, the time, counters and flags.
        noise: ``float64 [num_tasks]`` completion noise per decision with instant travel,
            ``None`` with a collision-aware executor.
    """

    arrays: dict[str, np.ndarray]
    scalars: dict[str, Any]
    noise: np.ndarray | None


class WarehouseSim(Reassignment):
    """One warehouse episode at a time, stepped one decision at a time.

    Args:
        config: Simulator parameters.
        layout: The grid.
        distance_model: Distances on ``layout`` (the policies measure with it; kept as
            ``distance_model``).
        tasks: The task stream.
        buffers: Where to keep the robot and queue state; allocated when ``None``.
        executor: How robots travel (a fresh one per simulator);
            :class:`~rtaw_marl.sim.execution.InstantTravel` when ``None``.

    Public state after :meth:`reset` (read-only views; do not modify):
        robot: Index of the selected robot.
        time: Current decision time.
        robot_xy: ``int64 [M, 2]`` cell of each robot when it is next free.
        robot_free_at: ``float64 [M]`` time each robot becomes free.
        queue_ids: ``int64 [N]`` task id per slot, ``-1`` for an empty slot.
        queue_mask: ``bool [N]`` which slots hold a task (the legal actions).
        queue_rows: ``int64 [N, 4]`` task row per slot, zeros for an empty slot.
        queue_length: ``float64 [N]`` task length per slot, 0 for an empty slot.
        queue_holder: ``int64 [N]`` with ``sim.reassign``: the robot holding the slot's
            task (assigned, not yet picked up), ``-1`` otherwise; such a slot keeps its
            row and length and is not in :attr:`queue_mask`.
        tasks: ``int64 [T, 4]`` every task of the episode in arrival order.
        task_length: ``float64 [T]`` origin -> destination distance per task (NaN until
            the task enters the queue).
        done: The episode is over; ``truncated`` tells whether by the decision limit.
    """

    def __init__(
        self,
        config: SimConfig,
        layout: Layout,
        distance_model: DistanceModel,
        tasks: TaskStream,
        buffers: SimBuffers | None = None,
        executor: Executor | None = None,
    ) -> None:
        if distance_model.layout is not layout:
            raise ConfigError("the distance model was built for a different layout")
        if config.num_robots > len(layout.main_cells) and config.robot_starts is None:
            raise ConfigError(
                f"sim.num_robots={config.num_robots} exceeds the {len(layout.main_cells)} free "
                f"cells of layout {layout.name!r}"
            )
        if tasks.refill_same_slot and config.refill == "finish":
            raise ConfigError("sim.refill=finish cannot refill a slot with its own task")
        if tasks.refill_same_slot and tasks.max_tasks is None:
            fixed = getattr(tasks, "tasks", None)
            if fixed is not None and len(fixed) != config.queue_len:
                raise ConfigError(
                    f"this task stream refills each slot with its own task: sim.queue_len must "
                    f"be {len(fixed)}, got {config.queue_len}"
                )
        self.config = config
        self.layout = layout
        self.distance_model = distance_model
        self.stream = tasks
        self.num_robots = config.num_robots
        self.queue_len = config.queue_len
        self._paper = config.episode_mode == "paper"
        self._horizon = config.horizon if config.episode_mode == "horizon" else None
        self._refill_on_finish = config.refill == "finish"
        self._num_decisions = config.num_tasks
        self._reward_code = REWARDS.index(config.reward)
        self._slots = distance_model.target_slots(config.queue_len)
        self._queue_distances = QueueDistances(self._slots, config.num_robots)
        if buffers is None:
            buffers = SimBuffers.allocate(config.num_robots, config.queue_len)
        buffers.check(config.num_robots, config.queue_len)
        self.robot_xy = buffers.robot_xy
        self.robot_free_at = buffers.robot_free_at
        self.queue_mask = buffers.queue_mask
        self.queue_rows = buffers.queue_rows
        self.queue_length = buffers.queue_length
        self.queue_ids = np.full(config.queue_len, -1, dtype=np.int64)
        self.queue_holder = np.full(config.queue_len, -1, dtype=np.int64)
        self._executor = InstantTravel() if executor is None else executor
        self._executor.bind(config, layout, distance_model)
        self._reassign = config.reassign
        seconds = None if config.time_budget_ms is None else config.time_budget_ms / 1e3
        self._clock = DecisionClock(config.decision_budget, seconds)
        if self._clock.active and not self._executor.releases:
            raise ConfigError(
                "sim.decision_budget and sim.time_budget_ms need an executor that moves "
                f"robots timestep by timestep (navigator=pibt), not {self._executor.name!r}"
            )
        if self._reassign and not self._executor.releases:
            raise ConfigError(
                f"sim.reassign=true needs an executor that moves robots timestep by "
                f"timestep (navigator=pibt), not {self._executor.name!r}; or sim.reassign=false"
            )
        self.done = True
        self.truncated = False

    # ------------------------------------------------------------------ reset
    def reset(self, seed: int | None = None) -> None:
        """Start a new episode; the same ``seed`` gives the same tasks, starts and noise."""
        cfg = self.config
        m, n = self.num_robots, self.queue_len
        task_rng, start_rng, noise_rng = (
            np.random.default_rng(s) for s in np.random.SeedSequence(seed).spawn(3)
        )
        total = cfg.num_tasks + n if self._paper else cfg.num_tasks
        tasks, starts = self._draw(task_rng, start_rng, total)

        self.tasks = tasks
        # Lengths are measured when a task enters the queue, from its slot's field.
        self.task_length = np.full(total, np.nan)
        self.robot_xy[:] = starts
        self.robot_start_xy = starts.copy()
        self.robot_free_at[:] = cfg.robot_free_times if cfg.robot_free_times is not None else 0.0
        self.robot_busy = np.zeros(m, dtype=np.float64)

        # Per-task records, filled as tasks arrive and are assigned.
        self.task_arrival = np.full(total, np.nan)
        self.task_assigned = np.full(total, np.nan)
        self.task_ttd = np.full(total, np.nan)
        self.task_finished = np.full(total, np.nan)
        self.task_robot = np.full(total, -1, dtype=np.int64)
        self.task_moved = np.full(total, np.nan)  # when the task last changed hands

        self.queue_ids[:] = -1
        self.queue_holder[:] = -1
        self.queue_mask[:] = False
        self.queue_rows[:] = 0
        self.queue_length[:] = 0.0
        self._queue_distances.clear()
        first = min(n, total)
        self.task_arrival[:first] = 0.0
        for slot in range(first):
            self._enqueue(slot, slot)
        self._next_task = first

        records = EpisodeRecords(
            tasks=self.tasks,
            task_arrival=self.task_arrival,
            task_assigned=self.task_assigned,
            task_ttd=self.task_ttd,
            task_finished=self.task_finished,
            task_robot=self.task_robot,
            robot_busy=self.robot_busy,
            robot_free_at=self.robot_free_at,
        )
        self._executor.reset(starts, records, noise_rng)
        self._owed = np.zeros(m, dtype=bool)
        self.decisions = 0
        self._retaken = 0  # decisions that took a task given back (reassignment)
        self.done = False
        self.truncated = False
        self.last_ttd = 0.0
        self._clock.reset()
        self._select_next_robot(0.0)

    def _draw(
        self, task_rng: np.random.Generator, start_rng: np.random.Generator, total: int
    ) -> tuple[np.ndarray, np.ndarray]:
        """The episode's ``total`` tasks ``int64 [T, 4]`` and robot starts ``int64 [M, 2]``,
        checked: on free cells, all mutually reachable."""
        tasks = np.asarray(self.stream.generate(task_rng, self.layout, total), dtype=np.int64)
        self.layout.check_cells(tasks[:, :2], "origin of task")
        self.layout.check_cells(tasks[:, 2:], "destination of task")
        if self.config.robot_starts is not None:
            starts = np.asarray(self.config.robot_starts, dtype=np.int64)
            self.layout.check_cells(starts, "start of robot")
        elif (given := self.stream.starts(start_rng, self.layout, self.num_robots)) is not None:
            starts = np.asarray(given, dtype=np.int64)
        else:
            cells = self.layout.main_cells
            starts = cells[start_rng.choice(len(cells), size=self.num_robots, replace=False)]
        k, kinds = len(tasks), ("origin of task", "destination of task", "start of robot")
        self.distance_model.check_connected(
            np.concatenate([tasks[:, :2], tasks[:, 2:], starts]),
            lambda i: f"{kinds[min(i // k, 2)]} {i - min(i // k, 2) * k}",
        )
        return tasks, starts

    # ------------------------------------------------------------------ queries
    def robot_distances(self, robot: int | None = None) -> np.ndarray:
        """Distances ``float64 [N]`` from a robot (default: the selected one) to each queued origin.

        Entries of empty slots are meaningless; mask them with :attr:`queue_mask`.
        Cached for the selected robot at the current decision.
        """
        if robot is not None and robot != self.robot:
            x, y = self.robot_xy[robot]
            return self._slots.distances_from_one(int(x), int(y))
        if self._dist is None:
            x, y = self.robot_xy[self.robot]
            self._dist = self._slots.distances_from_one(int(x), int(y))
        return self._dist

    def distance_matrix(self, slots: np.ndarray | None = None, *, copy: bool = True) -> np.ndarray:
        """Distances ``float64 [M, N]`` from every robot's cell to each queued origin
        (``[M, K]`` to the origins of ``slots int [K]`` only, when given).

        The whole matrix is kept between decisions and updated where robots or slots
        changed (:class:`~rtaw_marl.sim.queue_distances.QueueDistances`); ``copy=False``
        returns the kept matrix itself: read it before the next step, never write it."""
        if slots is not None:
            return self._slots.distances_from(self.robot_xy, slots)
        kept = self._queue_distances.fleet(self.robot_xy)
        return kept.copy() if copy else kept

    def free_robots(self) -> np.ndarray:
        """``int64 [F]`` the robots free at the current decision, the selected one
        included, ascending (under lifelong PIBT a robot delayed by traffic is busy past
        its planned free time)."""
        known = self._executor.free_robots(self.time)
        if known is None:
            known = np.flatnonzero(self.robot_free_at <= self.time + 1e-9)
        return np.union1d(known, [self.robot]).astype(np.int64)

    def robot_distances_many(self, robots: np.ndarray, slots: np.ndarray) -> np.ndarray:
        """Distances ``float64 [R, K]`` from the cells of ``robots int [R]`` to the
        origins of ``slots int [K]`` (a few robots against a large pool: the fields of
        the robots' cells, not of every slot, when the slots keep cells)."""
        return self._slots.distances_from(self.robot_xy[np.asarray(robots)], slots)

    def chain_distances(self) -> np.ndarray:
        """Distances ``float64 [N, N]`` from each queued destination (rows) to each queued
        origin (columns): how well one task leads into another. Empty slots: meaningless."""
        return self._slots.distances_from(self.queue_rows[:, 2:])

    def chain_nearest(self, slots: np.ndarray | None = None, *, copy: bool = True) -> np.ndarray:
        """``float64 [N]`` (or ``[K]`` for ``slots int [K]``): the distance from each
        queued destination to the nearest origin of *another* queued task, ``inf`` when
        there is none (or the slot is empty). Kept per slot between decisions: ``O(N)``
        distance lookups for each slot changed since, not ``O(K N)`` each time."""
        if slots is None:
            kept = self._queue_distances.chain_nearest(self.queue_rows, self.queue_mask)
            return kept.copy() if copy else kept  # copy=False: as distance_matrix's
        return self._queue_distances.nearest_of(slots, self.queue_rows, self.queue_mask)

    def queue_waits(self) -> np.ndarray:
        """``float64 [N]`` time each queued task has waited in the queue (0 when empty)."""
        arrival = self.task_arrival[np.maximum(self.queue_ids, 0)]
        return np.where(self.queue_mask, self.time - arrival, 0.0)

    def queue_tasks(self) -> np.ndarray:
        """A copy of :attr:`queue_rows`: ``int64 [N, 4]``, zeros for empty slots."""
        return self.queue_rows.copy()

    def queue_lengths(self) -> np.ndarray:
        """A copy of :attr:`queue_length`: ``float64 [N]``, 0 for empty slots."""
        return self.queue_length.copy()

    def robot_remaining(self) -> np.ndarray:
        """``float64 [M]`` time until each robot is free (0 for the selected robot)."""
        return self.robot_free_at - self.time

    # ------------------------------------------------------------------ step
    def step(self, action: int) -> float:
        """Give queued task ``action`` to the selected robot and advance to the next decision.

        Returns:
            The reward of this decision (minus the TTD of the chosen task by default).

        Raises:
            InvalidActionError: ``action`` is not an integer scalar (see
                :func:`~rtaw_marl.sim.inputs.slot_index`), is out of range or names an
                empty slot, or the episode is over.
        """
        if self.done:
            raise InvalidActionError("the episode is over; call reset()")
        slot = slot_index(action, self.queue_len)
        if not self.queue_mask[slot]:
            if not (self._reassign and self.queue_holder[slot] >= 0):
                raise InvalidActionError(f"action {slot} names an empty queue slot")
            self._take_held(slot)

        robot, now = self.robot, self.time
        self._clock.charge(now)
        task = int(self.queue_ids[slot])
        # A task given back and taken again is no new task of the stream: the episode's
        # num_tasks counts tasks, not decisions (a rule re-pairing robots each timestep
        # makes several decisions per task).
        self._retaken += int(not np.isnan(self.task_moved[task]))
        dist = self._dist if self._dist is not None else self.robot_distances()
        ttd = float(dist[slot])
        length = float(self.queue_length[slot])
        ttd, finish = self._executor.assign(robot, now, task, self.queue_rows[slot], ttd, length)

        self.task_assigned[task] = now
        self.task_ttd[task] = ttd
        self.task_finished[task] = finish
        self.task_robot[task] = robot
        self.robot_xy[robot] = self.queue_rows[slot, 2:]
        self._queue_distances.robot_moved(robot)
        # Busy from assignment until free again (noise included), so idle >= 0.
        self.robot_busy[robot] += finish - now
        if self._refill_on_finish:
            # LoRR's window: the task stays revealed until it is finished (and, with
            # reassignment, in its slot until it is picked up).
            if self._reassign and self.executor.started(np.array([task]))[0]:
                self._empty(slot)
            elif self._reassign:
                self._hold(slot, robot)
            else:
                self._empty(slot)
            self._owed[robot] = True
        else:
            self._refill(slot, task, now)

        self.decisions += 1
        self.last_ttd = ttd
        if self.decisions - self._retaken >= self._num_decisions:
            self.done = True
            self.truncated = self._paper or self._horizon is not None
            self._dist = None  # the acting robot has moved: its cached distances are stale
            if self._horizon is not None:
                self._executor.finish_at(self._horizon)  # the stream ran out before T
            else:
                self._executor.finish(now)
        else:
            self._select_next_robot(now)

        if self._reward_code == 0:
            return -ttd
        if self._reward_code == 1:
            return -length
        if self._reward_code == 2:
            return -(ttd + length)
        return -(ttd + length / PAIR_WEIGHT)

    def _drop_started(self) -> None:
        """Held tasks picked up since the last decision leave their slots."""
        held = np.flatnonzero(self.queue_holder >= 0)
        if len(held):
            for slot in held[self._executor.started(self.queue_ids[held])].tolist():
                self._empty(slot)

    def _empty(self, slot: int) -> None:
        self._queue_distances.slot_changed(slot)
        self.queue_holder[slot] = -1
        self.queue_ids[slot] = -1
        self.queue_mask[slot] = False
        self.queue_rows[slot] = 0
        self.queue_length[slot] = 0.0

    def _refill(self, slot: int, task: int, now: float) -> None:
        new = self._next_task
        if new >= len(self.tasks):
            self._empty(slot)
            return
        if self.stream.refill_same_slot:
            # The slot keeps its task: the paper's two-task queue always holds both tasks.
            self.tasks[new] = self.tasks[task]
        self._next_task = new + 1
        self.task_arrival[new] = now
        self._enqueue(slot, new)

    def _enqueue(self, slot: int, task: int) -> None:
        row = self.tasks[task]
        ox, oy, dx, dy = row.tolist()
        self._slots.set(slot, ox, oy)
        self._queue_distances.slot_changed(slot)
        # A task whose pickup is its delivery (LoRR's files hold some) takes one timestep,
        # as in LoRR (one errand checked per timestep), never zero: a robot at its cell
        # would otherwise finish the whole pool without time passing.
        length = self._slots.distance_to(slot, dx, dy) or 1.0
        self.task_length[task] = length
        self.queue_ids[slot] = task
        self.queue_mask[slot] = True
        self.queue_rows[slot] = row
        self.queue_length[slot] = length

    def _select_next_robot(self, now: float) -> None:
        if self._clock.spent(now):
            self._executor.defer()  # the free robots wait for the next timestep
        self.robot, self.time = self._executor.next_robot(now)
        self._dist = None
        if self._horizon is not None and self.time >= self._horizon:
            # The fixed horizon is reached before this robot's decision: the episode ends.
            self.done = self.truncated = True
            self._executor.finish_at(self._horizon)
            return
        if self._reassign:
            self._drop_started()
        if self._refill_on_finish and self._owed[self.robot]:
            # The robot's last task is finished now: one more task is revealed.
            self._owed[self.robot] = False
            empty = np.flatnonzero(~self.queue_mask & (self.queue_holder < 0))
            if len(empty):
                self._refill(int(empty[0]), -1, self.time)
        self._clock.ask()

    @property
    def navigator(self) -> DistanceModel:
        """Deprecated alias of :attr:`distance_model` (the ``navigator`` option names a
        distance model and an executor; this is the distance model only)."""
        warnings.warn(
            "WarehouseSim.navigator is deprecated, use .distance_model",
            DeprecationWarning,
            stacklevel=2,
        )
        return self.distance_model

    @property
    def executor(self) -> Executor:
        """How robots travel: its ``name``, ``collision_aware`` and episode ``stats()``."""
        return self._executor

    def schedule(self) -> Schedule:
        """The executed episode: every robot's cell at every second and each task's times.

        Raises:
            ConfigError: Robots move independently (the executor is not collision-aware).
            InvalidActionError: The episode is not over.
        """
        return self._executor.schedule()

    # ------------------------------------------------------------------ state
    def state(self) -> SimState:
        """A copy of everything the current episode has changed (for rollouts).

        Future tasks and, with instant travel, the future completion noise are included:
        a simulator that loads this state plays the same future as this one.
        """
        arrays = {k: np.array(getattr(self, k), copy=True) for k in _STATE_ARRAYS}
        scalars = {k: getattr(self, k) for k in _STATE_SCALARS}
        return SimState(arrays, scalars, self._executor.travel_noise())

    def load_state(self, state: SimState) -> None:
        """Continue from ``state`` (taken from a simulator of the same config and layout).

        Only instant travel can be restored; a collision-aware episode's state loads
        as instant travel without noise (its fleet's paths and waits are not modelled).
        The kept fleet and queue distances are refreshed where the state differs (the
        robots whose cell and the slots whose task changed), not recomputed whole: an
        outside simulator loaded every timestep (LoRR's, ``external.load_decisions``)
        changes a few of them.

        Raises:
            ConfigError: This simulator's executor is collision-aware.
        """
        before = (self.robot_xy.copy(), self.queue_rows.copy(), self.queue_mask.copy())
        for key, value in state.arrays.items():
            current = getattr(self, key, None)
            if current is not None and current.shape == value.shape:
                np.copyto(current, value)  # buffers may be views shared with a batch
            else:
                setattr(self, key, value.copy())
        for key, value in state.scalars.items():
            setattr(self, key, value)
        noise = state.noise
        if noise is None:
            noise = np.zeros(self.config.num_tasks)
        self._executor.load_travel(noise, self.decisions, self.robot_free_at)
        self._dist = None
        xy, rows, mask = before
        if xy.shape != self.robot_xy.shape or rows.shape != self.queue_rows.shape:
            changed = np.flatnonzero(self.queue_mask)
            self._queue_distances.clear()
        else:
            # A slot changed if it was filled or emptied, or holds another task's cells.
            new_rows = (self.queue_rows != rows).any(axis=1)
            changed = np.flatnonzero((mask != self.queue_mask) | (self.queue_mask & new_rows))
            self._queue_distances.slots_changed(changed)
            self._queue_distances.robots_moved(np.flatnonzero((self.robot_xy != xy).any(axis=1)))
        for slot in changed[self.queue_mask[changed]].tolist():
            ox, oy = self.queue_rows[slot, :2].tolist()
            self._slots.set(int(slot), ox, oy)

    # ------------------------------------------------------------------ results
    def metrics(self) -> EpisodeMetrics:
        """Metrics of the episode so far (final once :attr:`done`)."""
        return self._compute_metrics()[0]

    def robot_idle(self) -> np.ndarray:
        """Per-robot idle time ``float64 [M]`` within ``[0, makespan]``."""
        return self._compute_metrics()[1]

    def _compute_metrics(self) -> tuple[EpisodeMetrics, np.ndarray]:
        return compute_metrics(
            self.task_robot >= 0,
            self.task_ttd,
            self.task_length,
            self.task_arrival,
            self.task_assigned,
            self.task_finished,
            self.robot_busy,
            self.decisions,
            self._horizon,
        )
