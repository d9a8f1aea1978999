"""Any rtaw_marl policy as the task scheduler of LoRR's simulator, free of the start kit.

:class:`PolicyScheduler` keeps LoRR's revealed tasks in the queue slots of a
:class:`~rtaw_marl.sim.core.WarehouseSim` (the *mirror*, with instant travel on the
problem's map), and at each timestep loads the fleet as LoRR reports it
(:func:`~rtaw_marl.sim.external.load_decisions`): free robots where they stand, busy
robots at the delivery of their task, free after the shortest-path travel their task
had left when the robot was first seen with it (as the own simulator keeps a busy
robot's planned free time from its assignment: an estimate computed once per task,
not one distance field per busy robot and timestep, which at 5,000 robots cost more
than the timestep's share of the clock).
The free robots then decide in turn, lowest id first, through ``policy.act_sim``, the
fast path every policy has, each choice taking its task out of the queue.

LoRR's rules (its ``TaskManager``): one robot per task, and a robot keeps its task once
it has reached the first errand. This scheduler never reassigns: a robot with a task
keeps it, a free robot gets one of the unassigned tasks or none (``-1``). When the
timestep's share of the time limit runs out, the robots a policy has decided already (a
matched batch) take their tasks, and the others stay free until the next timestep
(counted as ``deferred``), as LoRR's default scheduler does; with
``overflow="nearest"`` they take the nearest open task instead
(:mod:`~rtaw_marl.integrations.lorr.overflow`, counted as ``overflowed``).

Locations are LoRR's linearized cells, ``row x width + column``; a task's errands are
visited in order; a task of more than two errands is one pickup (the first) and one
delivery (the last), its length the travel through all of them.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from rtaw_marl.errors import unknown_name
from rtaw_marl.integrations.lorr.overflow import OVERFLOWS, RESERVE, nearest_pairs
from rtaw_marl.policies.base import PlansAhead, Policy
from rtaw_marl.sim.core import WarehouseSim
from rtaw_marl.sim.external import DecisionState, load_decisions
from rtaw_marl.sim.layout import Layout

__all__ = ["PolicyScheduler", "SchedulerStats", "Timestep"]


@dataclass(frozen=True)
class Timestep:
    """What LoRR's shared environment says at one call of the scheduler.

    Attributes:
        time: ``curr_timestep``.
        locations: ``int64 [M]`` each robot's cell (linearized).
        schedule: ``int64 [M]`` each robot's task id, ``-1`` when free
            (``curr_task_schedule``).
        pool: Ids of the tasks revealed and not finished (``task_pool``'s keys).
        read_task: ``id -> (errands, t_revealed)`` for a task of ``pool`` (called once
            per task, when it first appears).
        progress: ``id -> idx_next_loc``, the errands of a task already reached (called
            for tasks not yet known to be picked up).
    """

    time: int
    locations: np.ndarray
    schedule: np.ndarray
    pool: Sequence[int]
    read_task: Callable[[int], tuple[Sequence[int], int]]
    progress: Callable[[int], int]


@dataclass
class SchedulerStats:
    """Counts over an episode (``asdict`` is what a run reports)."""

    calls: int = 0
    decisions: int = 0
    deferred: int = 0
    overflowed: int = 0
    reassigned: int = 0
    seconds: float = 0.0
    max_call_s: float = 0.0
    errors: list[str] = field(default_factory=list)


class PolicyScheduler:
    """LoRR's ``plan`` for an rtaw_marl policy.

    Args:
        policy: Any policy (``act_sim``).
        sim: The mirror: a simulator of the problem's map and ``M`` robots with instant
            travel, a queue as long as LoRR's window (``ceil(numTasksReveal x M)``),
            ``sim.num_tasks`` above ``M``; reset here.
        seed: Seeds the policy's tie-breaking.
        clock: Seconds (``time.perf_counter``).
        overflow: The robots not served in time: ``wait`` for the next timestep, or take
            the ``nearest`` open task (the policy then stops at ``1 - RESERVE`` of the
            budget).

    Raises:
        ConfigError: An unknown ``overflow`` (the message lists them).
    """

    def __init__(
        self,
        policy: Policy,
        sim: WarehouseSim,
        seed: int = 0,
        clock: Callable[[], float] = time.perf_counter,
        overflow: str = "wait",
    ) -> None:
        if overflow not in OVERFLOWS:
            raise unknown_name("overflow", overflow, list(OVERFLOWS))
        self.policy, self.sim, self.clock, self.overflow = policy, sim, clock, overflow
        self.width = sim.layout.width
        sim.reset(seed)
        if not sim.done:
            # The first decision compiles a learned policy: here, not in LoRR's first
            # timestep (which would run past its time limit).
            policy.reset(seed)
            policy.act_sim(sim)
        policy.reset(seed)
        n = sim.queue_len
        self._rows = np.zeros((n, 4), dtype=np.int64)
        self._length = np.zeros(n)
        self._arrival = np.zeros(n)
        self._slot_task = np.full(n, -1, dtype=np.int64)
        self._slot_of: dict[int, int] = {}
        self._free_slots = list(range(n - 1, -1, -1))
        self._tasks: dict[int, tuple[np.ndarray, np.ndarray, int]] = {}
        m = sim.num_robots
        self._robot_task = np.full(m, -1, dtype=np.int64)
        self._reached = np.zeros(m, dtype=np.int64)
        self._final = np.ones(m, dtype=bool)
        self._target = np.zeros(m, dtype=np.int64)
        self._rest = np.zeros(m)
        self._drop = np.zeros(m, dtype=np.int64)
        # Planned free and pickup times, from when each robot was first seen on its task.
        self._free_at = np.zeros(m)
        self._pickup_at = np.zeros(m)
        self.stats = SchedulerStats()

    @property
    def layout(self) -> Layout:
        """The problem's map (the mirror's)."""
        return self.sim.layout

    def preload(self, budget_s: float) -> int:
        """Compute the distance fields of the cells of the problem's first tasks, in
        LoRR's preprocessing time (the first timestep reveals a whole window of tasks).

        Returns:
            The cells whose fields were computed within ``budget_s`` seconds.
        """
        file_tasks = getattr(self.sim.stream, "tasks", None)
        distance_model = self.sim.distance_model
        if file_tasks is None or not hasattr(distance_model, "fields"):
            return 0
        first = np.asarray(file_tasks[: 2 * self.sim.queue_len]).reshape(-1, 2)
        _, at = np.unique(first[:, 1] * (1 << 20) + first[:, 0], return_index=True)
        cells = first[np.sort(at)]
        # Three quarters of the field cache at most: preloading must not evict itself.
        cells = cells[: max(0, 3 * getattr(distance_model, "_capacity", len(cells)) // 4)]
        deadline = self.clock() + budget_s
        done = 0
        while done < len(cells) and self.clock() < deadline:
            distance_model.fields(cells[done : done + 32])
            done = min(done + 32, len(cells))
        return done

    def plan(self, step: Timestep, budget_s: float) -> list[int]:
        """The schedule for this timestep: each robot's task id or ``-1``.

        Args:
            step: LoRR's state.
            budget_s: Seconds left for scheduling (robots not served by then wait).
        """
        start = self.clock()
        keep = RESERVE if self.overflow == "nearest" else 0.0
        deadline = start + (1.0 - keep) * budget_s
        schedule = np.asarray(step.schedule, dtype=np.int64)
        self._sync_pool(step)
        busy = np.flatnonzero(schedule >= 0)
        self._queue(set(self._tasks) - set(schedule[busy].tolist()))
        proposed = schedule.copy()
        if load_decisions(self.sim, self._state(step, schedule, busy)):
            self._decide(step.time, proposed, deadline)
        spent = self.clock() - start
        self.stats.calls += 1
        self.stats.seconds += spent
        self.stats.max_call_s = max(self.stats.max_call_s, spent)
        return proposed.tolist()

    def _decide(self, now: int, proposed: np.ndarray, deadline: float) -> None:
        sim = self.sim
        while not sim.done and sim.time <= now and sim.queue_mask.any():
            if self.clock() > deadline:
                self._overflow(now, proposed)
                return
            slot = int(self.policy.act_sim(sim))
            task = int(self._slot_task[slot])
            proposed[sim.robot] = task
            self.stats.decisions += 1
            sim.step(slot)
            self._release(task)

    def _overflow(self, now: int, proposed: np.ndarray) -> None:
        """The robots free and not served when the clock ran out: those the policy has
        decided already (a matched batch) take their tasks, the others wait or take the
        nearest open tasks (the mirror is not stepped: the next timestep loads them busy
        from LoRR's schedule)."""
        sim = self.sim
        open_slot = sim.queue_mask.copy()
        if isinstance(self.policy, PlansAhead):
            robots, slots = self.policy.pending(sim)
            proposed[robots] = self._slot_task[slots]
            open_slot[slots] = False
            self.stats.decisions += len(robots)
        waiting = np.flatnonzero((sim.robot_free_at <= now) & (proposed < 0))
        if self.overflow == "nearest" and len(waiting):
            open_slots = np.flatnonzero(open_slot)
            got = nearest_pairs(sim.robot_xy[waiting], sim.queue_rows[open_slots, :2])
            served = got >= 0
            proposed[waiting[served]] = self._slot_task[open_slots[got[served]]]
            self.stats.overflowed += int(served.sum())
            waiting = waiting[~served]
        self.stats.deferred += len(waiting)

    # ------------------------------------------------------------------ the pool
    def _sync_pool(self, step: Timestep) -> None:
        pool = set(int(t) for t in step.pool)
        for task in set(self._tasks) - pool:  # finished
            del self._tasks[task]
            self._release(task)
        new = sorted(pool - set(self._tasks))
        if not new:
            return
        errands, revealed = [], []
        for task in new:
            locs, t_revealed = step.read_task(task)
            errands.append(np.asarray(locs, dtype=np.int64))
            revealed.append(int(t_revealed))
        # One distance call for every leg of the new tasks.
        legs_from = np.concatenate([e[:-1] for e in errands])
        legs_to = np.concatenate([e[1:] for e in errands])
        legs = self._distance(legs_from, legs_to)
        at = 0
        for task, locs, t_revealed in zip(new, errands, revealed, strict=True):
            k = len(locs) - 1
            # Travel left after reaching errand i: the legs after it.
            rest = np.concatenate([np.cumsum(legs[at : at + k][::-1])[::-1], [0.0]])
            self._tasks[task] = (locs, rest, t_revealed)
            at += k

    def _queue(self, unassigned: set[int]) -> None:
        """Slots for the unassigned tasks, stable while a task waits."""
        for task in [t for t in self._slot_of if t not in unassigned]:
            self._release(task)
        new = sorted(unassigned - set(self._slot_of))
        if not new:
            return
        if len(new) > len(self._free_slots):
            raise RuntimeError(
                f"LoRR revealed more unassigned tasks than the {self.sim.queue_len} "
                "queue slots (the window ceil(numTasksReveal x M))"
            )
        slots = np.array([self._free_slots.pop() for _ in new], dtype=np.int64)
        records = [self._tasks[t] for t in new]
        ends = np.array([(locs[0], locs[-1]) for locs, _, _ in records], dtype=np.int64)
        self._rows[slots] = self._xy(ends).reshape(-1, 4)
        self._length[slots] = [rest[0] for _, rest, _ in records]
        self._arrival[slots] = [t_revealed for _, _, t_revealed in records]
        self._slot_task[slots] = new
        self._slot_of.update(zip(new, slots.tolist(), strict=True))

    def _release(self, task: int) -> None:
        slot = self._slot_of.pop(task, None)
        if slot is not None:
            self._slot_task[slot] = -1
            self._free_slots.append(slot)

    # ------------------------------------------------------------------ the fleet
    def _track(self, step: Timestep, schedule: np.ndarray) -> np.ndarray:
        """Per-robot errand progress: the next errand, the travel after it, the delivery.
        Returns the robots whose task changed since the last call, ``int64 [C]``."""
        changed = np.flatnonzero(schedule != self._robot_task)
        self._robot_task[changed] = schedule[changed]
        self._reached[changed] = 0
        self._final[changed] = schedule[changed] < 0
        # LoRR is asked once per robot on its way to an errand that is not its last
        # (its pickup): a call into the start kit per such robot, not per timestep.
        for robot in np.flatnonzero(~self._final).tolist():
            task = int(self._robot_task[robot])
            locs, rest, _ = self._tasks[task]
            reached = min(int(step.progress(task)), len(locs) - 1)
            self._reached[robot] = reached
            self._target[robot] = locs[reached]
            self._rest[robot] = rest[reached]
            self._drop[robot] = locs[-1]
            self._final[robot] = reached == len(locs) - 1
        return changed

    def _state(self, step: Timestep, schedule: np.ndarray, busy: np.ndarray) -> DecisionState:
        changed = self._track(step, schedule)
        locations = np.asarray(step.locations, dtype=np.int64)
        new = changed[schedule[changed] >= 0]
        to_next = self._distance(locations[new], self._target[new])
        self._free_at[new] = step.time + np.maximum(to_next + self._rest[new], 1.0)
        self._pickup_at[new] = step.time + np.maximum(to_next, 1.0)
        robot_xy = self._xy(locations)
        free_at = np.full(len(locations), float(step.time))
        # A robot delayed past its planned time is still busy: free the next timestep.
        free_at[busy] = np.maximum(self._free_at[busy], step.time + 1.0)
        robot_xy[busy] = self._xy(self._drop[busy])
        heading = self._reached[busy] == 0
        robots = busy[heading]
        pickups = self._xy(self._target[robots])
        return DecisionState(
            time=float(step.time),
            robot_xy=robot_xy,
            robot_free_at=free_at,
            queue_rows=self._rows,
            queue_mask=self._slot_task >= 0,
            queue_length=self._length,
            queue_arrival=self._arrival,
            heading_rows=np.concatenate([pickups, self._xy(self._drop[robots])], axis=1),
            heading_robot=robots,
            heading_pickup_at=np.maximum(self._pickup_at[robots], step.time + 1.0),
        )

    def _xy(self, locs: np.ndarray) -> np.ndarray:
        locs = np.asarray(locs, dtype=np.int64)
        return np.stack([locs % self.width, locs // self.width], axis=-1)

    def _distance(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        if not len(a):
            return np.zeros(0)
        return self.sim.distance_model.distance(self._xy(a), self._xy(b))


def stats_dict(stats: SchedulerStats) -> Mapping[str, object]:
    """The counts as a JSON object."""
    return {
        "calls": stats.calls,
        "decisions": stats.decisions,
        "deferred": stats.deferred,
        "overflowed": stats.overflowed,
        "reassigned": stats.reassigned,
        "seconds": round(stats.seconds, 3),
        "max_call_s": round(stats.max_call_s, 4),
        "errors": list(stats.errors),
    }
