"""Lifelong PIBT execution (``navigator=pibt``): every robot moves one cell per timestep.

Unlike SIPP and CBS, which plan a whole path per task, PIBT (priority inheritance with
backtracking; Okumura et al., AIJ 2022) plans one timestep for the whole fleet at a
time (:func:`~rtaw_marl.sim.mapf._pibt.pibt_step`), so its cost per timestep is linear
in the fleet and does not grow with the horizon: it is what the League of Robot Runners'
default planner builds on, for 10,000 robots.

Each assigned robot walks to its task's origin, then to its destination, along its
goal's BFS field; a robot without a task keeps its cell unless pushed. Priorities are
the timesteps since a robot's goal last changed (ties: the lower id), so a robot that
is kept waiting gains priority until it moves first, and a robot with a goal gains 10
more for every timestep it spends on a dead-end cell (LoRR kit's planner: it must back
out before the robots queued behind it can move). With ``patience`` set, a busy robot
that has not got nearer its goal for that many timesteps is *stuck* and takes a random
priority each timestep (priority rotation), which breaks standoffs on maps without
dead-end bonuses to do it; at 10,000 robots it scatters the queues and deepens the jams,
so LoRR's model (the default) has none. The TTD of a task is its pickup time minus its
assignment time, waits included; the robot is free at the delivery time. Decisions are
taken when a robot is free, in order of robot id within a timestep.

Two options bring it to the League of Robot Runners' rules and planner:
``navigator.turns`` gives robots LoRR's headings and quarter turns
(:mod:`~rtaw_marl.sim.mapf._turns`), and ``navigator.guidance`` steers them along
congestion-aware guide paths, as LoRR's default planner does
(:mod:`~rtaw_marl.sim.mapf._guidance`): without it, opposite streams meet head-on.

What is guaranteed: every timestep is free of vertex and swap conflicts (by
construction, and checked by :func:`~rtaw_marl.sim.mapf.conflicts.check_schedule` on
every recorded episode). What is not: PIBT reaches every goal only on graphs where
every edge lies on a cycle; elsewhere robots can deadlock or livelock (rotation
recovers from most standoffs, not from two robots that must pass in a one-wide
corridor). :meth:`PIBTExecutor.stats` reports the longest any robot waited for its goal
to change (``max_stall``) and the timesteps with a stuck robot (``rotations``); a
timestep limit without any robot reaching a goal raises
:class:`~rtaw_marl.errors.PlanningError` naming it.
"""

from __future__ import annotations

import heapq
from collections import OrderedDict
from collections.abc import Callable

import numpy as np

from rtaw_marl.errors import ConfigError, InvalidActionError, PlanningError
from rtaw_marl.sim.distances import DistanceModel, GridDistance
from rtaw_marl.sim.execution import EpisodeRecords, Executor, SimSettings, check_whole_seconds
from rtaw_marl.sim.layout import Layout
from rtaw_marl.sim.mapf._pibt import bfs_compact, compact_graph, pibt_step
from rtaw_marl.sim.mapf._turns import FORWARD, WAIT, turn_step
from rtaw_marl.sim.mapf.guide_paths import GuidePaths
from rtaw_marl.sim.mapf.schedule import Schedule

__all__ = ["PIBTExecutor"]

_IDLE, _TO_PICKUP, _TO_DELIVERY = 0, 1, 2
#: Priority a busy robot gains per timestep on a dead-end cell (LoRR kit's planner).
_DEAD_END_BONUS = 10


class _Fields:
    """BFS fields of goal cells, shared by robots with the same goal and kept (up to a
    capacity) after their last robot leaves, so a popular cell is searched once."""

    def __init__(
        self, nbr: np.ndarray, capacity: int, search: Callable[[int, np.ndarray], None]
    ) -> None:
        self.nbr = nbr
        self.search = search
        cells = nbr.shape[0]
        # int16 halves the memory of 10,000 fields; a path longer than 32,766 steps on
        # a grid this size is refused rather than wrapped.
        self.dtype = np.int16 if cells < 2**15 else np.int32
        self.store = np.zeros((0, cells), dtype=self.dtype)
        self.capacity = capacity
        self.slot_of: dict[int, int] = {}
        self.cell_of: list[int] = []
        self.refs: list[int] = []
        self.idle: OrderedDict[int, None] = OrderedDict()  # unused slots, oldest first
        self._scratch = np.empty(cells, dtype=np.int32)
        self.searches = 0

    def acquire(self, cell: int) -> int:
        slot = self.slot_of.get(cell)
        if slot is None:
            slot = self._new_slot()
            self.search(cell, self._scratch)
            self.searches += 1
            self.store[slot] = self._scratch
            self.slot_of[cell] = slot
            self.cell_of[slot] = cell
        self.idle.pop(slot, None)
        self.refs[slot] += 1
        return slot

    def release(self, slot: int) -> None:
        self.refs[slot] -= 1
        if self.refs[slot] == 0:
            self.idle[slot] = None

    def _new_slot(self) -> int:
        if len(self.cell_of) < self.capacity:
            if len(self.cell_of) == len(self.store):
                grown = np.zeros((max(16, 2 * len(self.store)), self.store.shape[1]), self.dtype)
                grown[: len(self.store)] = self.store
                self.store = grown
            self.cell_of.append(-1)
            self.refs.append(0)
            return len(self.cell_of) - 1
        if not self.idle:
            raise PlanningError("pibt: every goal field is in use (more goals than capacity)")
        slot, _ = self.idle.popitem(last=False)
        del self.slot_of[self.cell_of[slot]]
        return slot


class PIBTExecutor(Executor):
    """Lifelong PIBT on the layout's free cells (4-connected, one move per second).
    Built by :class:`~rtaw_marl.sim.options.PIBTConfig` (``navigator=pibt``), which holds
    the defaults.

    Args:
        stall_limit: Timesteps without any robot reaching a goal before the episode is
            declared deadlocked (:class:`~rtaw_marl.errors.PlanningError`).
        patience: Timesteps a busy robot may go without getting nearer its goal before
            it is *stuck*: stuck robots take random priorities each timestep (priority
            rotation); ``None``: no rotation.
        record: Keep every robot's cell at every timestep (for :meth:`schedule` and the
            conflict checker): ``4 M`` bytes per timestep.
        turns: LoRR's action model (:mod:`~rtaw_marl.sim.mapf._turns`): robots start
            facing east, move forward only, and a quarter turn takes a timestep.
            ``False``: they move to any neighbouring cell without turning.
        guidance: Traffic-flow guidance (:mod:`~rtaw_marl.sim.mapf._guidance`): the
            cost of one other robot's guide path using an edge the other way; ``0``:
            none (robots follow shortest paths).
        guide_replans: Guide paths re-planned per timestep on the current flows, the
            longest unchanged first (besides those that must be).
    """

    name = "pibt"
    releases = True

    def __init__(
        self, *, stall_limit: int, patience: int | None, record: bool, turns: bool,
        guidance: float,
        guide_replans: int,
    ) -> None:  # fmt: skip
        checked = [("stall_limit", stall_limit)]
        if patience is not None:
            checked.append(("patience", patience))
        for key, value in checked:
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise ConfigError(f"navigator.{key} must be a positive integer, got {value!r}")
        if not isinstance(turns, bool):
            raise ConfigError(f"navigator.turns must be true or false, got {turns!r}")
        self.stall_limit = stall_limit
        self.patience = patience
        self.record = bool(record)
        self.turns = turns
        self.guidance = float(guidance)
        self.guide_replans = int(guide_replans)
        self._bound = False

    @property
    def collision_aware(self) -> bool:
        return True

    @property
    def keeps_schedule(self) -> bool:
        return self.record

    def bind(self, config: SimSettings, layout: Layout, distance_model: DistanceModel) -> None:
        if self._bound:
            raise ConfigError("executor 'pibt' already belongs to a simulator; make one each")
        check_whole_seconds(config, self.name)
        self._bound = True
        self.index, self.cells, self.nbr = compact_graph(layout.obstacles)
        self._dead_end = (self.nbr >= 0).sum(axis=1) == 1
        # The distance model's fields are the same BFS distances: taking them from its cache
        # shares each search with the policy's queries (a robot's decision is at the
        # cell whose field it just followed).
        self._model = distance_model if isinstance(distance_model, GridDistance) else None
        if self._model is not None:
            self._padded = self._model._padded_index(self.cells)
        self.num_robots = config.num_robots
        # A fixed-horizon episode stops moving at T even when no robot is free then.
        self.horizon = config.horizon if config.episode_mode == "horizon" else None

    def reset(self, starts: np.ndarray, records: EpisodeRecords, rng: np.random.Generator) -> None:
        m = self.num_robots
        starts = np.asarray(starts, dtype=np.int64).reshape(-1, 2)
        self.pos = self.index[starts[:, 1], starts[:, 0]].astype(np.int64)
        if len(np.unique(self.pos)) < m:
            raise ConfigError("navigator 'pibt' keeps robots on distinct cells: two start together")
        self.rec, self.rng = records, rng
        self.fields = _Fields(self.nbr, capacity=m + 4096, search=self._search)
        self.t = 0
        self.phase = np.zeros(m, dtype=np.int8)
        self.task = np.full(m, -1, dtype=np.int64)
        self.goal = np.full(m, -1, dtype=np.int64)  # compact goal cell
        self.delivery = np.full(m, -1, dtype=np.int64)
        self.goal_field = np.full(m, -1, dtype=np.int64)
        self.since = np.zeros(m, dtype=np.int64)
        self.best = np.zeros(m, dtype=np.int64)  # nearest the goal so far
        self.stuck = np.zeros(m, dtype=np.int64)  # timesteps without getting nearer
        self.boost = np.zeros(m, dtype=np.int64)  # dead-end bonus since the goal changed
        self.rotations = 0
        self.occ_now = np.full(len(self.cells), -1, dtype=np.int64)
        self.occ_now[self.pos] = np.arange(m)
        self.occ_next = np.full(len(self.cells), -1, dtype=np.int64)
        self.nxt = np.empty(m, dtype=np.int64)
        self.heading = np.zeros(m, dtype=np.int64)  # LoRR's robots start facing east
        self.target = np.full(m, -1, dtype=np.int64)  # committed next cells (turns)
        self.action = np.full(m, WAIT, dtype=np.int64)
        self.turn_actions = 0
        self.released = 0
        self.deferred = 0
        self.deferred_robots: list[int] = []
        self.guides = GuidePaths(self.nbr, m, self.guidance, self.guide_replans)
        self.free = [int(r) for r in np.flatnonzero(records.robot_free_at <= 0)]
        heapq.heapify(self.free)
        self.waiting = sorted(
            (float(t), int(r)) for r, t in enumerate(records.robot_free_at) if t > 0
        )
        n = len(records.tasks)
        self.pickup_at = np.full(n, -1, dtype=np.int64)
        self.delivered_at = np.full(n, -1, dtype=np.int64)
        self.trace: list[np.ndarray] = [self.pos.astype(np.int32)] if self.record else []
        self.heading_trace: list[np.ndarray] = [self.heading.astype(np.int8)]
        self.max_stall = 0
        self._done = False

    def assign(
        self, robot: int, now: float, task: int, row: np.ndarray, distance: float, length: float
    ) -> tuple[float, float]:
        if int(now) != self.t:
            raise InvalidActionError(f"pibt: robot {robot} assigned at {now}, now is {self.t}")
        ox, oy, dx, dy = row.tolist()
        self.task[robot] = task
        self.phase[robot] = _TO_PICKUP
        self._set_goal(robot, int(self.index[oy, ox]))
        self.delivery[robot] = int(self.index[dy, dx])
        if self.pos[robot] == self.goal[robot]:
            self._picked_up(robot)
        self.rec.robot_free_at[robot] = now + distance + length
        return distance, now + distance + length

    def release(self, robot: int, now: float) -> np.ndarray:
        if int(now) != self.t or self.phase[robot] != _TO_PICKUP:
            raise InvalidActionError(
                f"pibt: robot {robot} has no task to give up at {now} (t={self.t})"
            )
        self.phase[robot] = _IDLE
        self.task[robot] = -1
        self._set_goal(robot, -1)
        self.rec.robot_free_at[robot] = self.t
        self.released += 1
        heapq.heappush(self.free, robot)
        return self.cells[self.pos[robot]].astype(np.int64)

    def defer(self) -> None:
        self.deferred += len(self.free)
        self.deferred_robots.extend(self.free)
        self.free = []

    def started(self, tasks: np.ndarray) -> np.ndarray:
        return self.pickup_at[np.asarray(tasks, dtype=np.int64)] >= 0

    def positions(self, robots: np.ndarray) -> np.ndarray:
        """``int64 [R, 2]`` the cells ``(x, y)`` where ``robots`` stand now."""
        return self.cells[self.pos[np.asarray(robots, dtype=np.int64)]].astype(np.int64)

    def next_robot(self, now: float) -> tuple[int, float]:
        quiet = 0
        while not self.free:
            while self.waiting and self.waiting[0][0] <= self.t:
                heapq.heappush(self.free, self.waiting.pop(0)[1])
            if self.free:
                break
            if self.horizon is not None and self.t >= self.horizon:
                return 0, float(self.t)  # the simulator ends the episode at T
            events = self._step()
            if self.deferred_robots:  # their timestep's budget was spent: asked now
                self.free.extend(self.deferred_robots)
                heapq.heapify(self.free)
                self.deferred_robots = []
            quiet = 0 if events else quiet + 1
            if quiet > self.stall_limit:
                raise PlanningError(
                    f"pibt: no robot reached its goal in {self.stall_limit} timesteps "
                    f"(t={self.t}): a deadlock or livelock on this map"
                )
        return heapq.heappop(self.free), float(self.t)

    def free_robots(self, now: float) -> np.ndarray:
        # Planned free times are estimates: a robot delayed by traffic is still busy
        # after its own. The free robots are those delivered and not yet asked.
        del now
        return np.asarray(self.free, dtype=np.int64)

    def finish(self, now: float) -> None:
        """Run until every assigned task is delivered, then record the executed times."""
        quiet = 0
        while (self.phase != _IDLE).any():
            quiet = 0 if self._step() else quiet + 1
            if quiet > self.stall_limit:
                raise PlanningError(
                    f"pibt: no robot reached its goal in {self.stall_limit} timesteps while "
                    f"finishing (t={self.t}): a deadlock or livelock on this map"
                )
        self._final_busy(self.t)
        self._done = True

    def finish_at(self, horizon: int) -> None:
        """End a fixed-horizon episode at ``horizon``: move on without new decisions
        until then; tasks not delivered stay unfinished, and those not picked up count
        their wait until the horizon."""
        while self.t < horizon and (self.phase != _IDLE).any():
            self._step()
        rec = self.rec
        late = self.task[self.phase == _TO_PICKUP]
        rec.task_ttd[late] = horizon - rec.task_assigned[late]
        rec.task_finished[self.task[self.phase != _IDLE]] = np.nan  # not delivered
        self._final_busy(horizon)
        self._done = True

    def _final_busy(self, end: int) -> None:
        """Each robot's time on tasks, from assignment to delivery (or ``end``)."""
        rec = self.rec
        served = np.flatnonzero(rec.task_robot >= 0)
        until = np.where(np.isnan(rec.task_finished[served]), end, rec.task_finished[served])
        rec.robot_busy[:] = np.bincount(
            rec.task_robot[served],
            weights=np.minimum(until, end) - rec.task_assigned[served],
            minlength=self.num_robots,
        )

    def _search(self, cell: int, out: np.ndarray) -> None:
        if self._model is None:
            bfs_compact(self.nbr, cell, out)
        else:
            x, y = self.cells[cell]
            out[:] = self._model.field(int(x), int(y))[self._padded]

    def _set_goal(self, robot: int, cell: int) -> None:
        if self.goal_field[robot] >= 0:
            self.fields.release(int(self.goal_field[robot]))
        self.goal[robot] = cell
        self.goal_field[robot] = -1 if cell < 0 else self.fields.acquire(cell)
        self.since[robot] = 0
        self.stuck[robot] = 0
        self.best[robot] = 1 << 30
        self.boost[robot] = 0

    def _picked_up(self, robot: int) -> None:
        task = int(self.task[robot])
        self.pickup_at[task] = self.t
        self.rec.task_ttd[task] = self.t - self.rec.task_assigned[task]
        self.phase[robot] = _TO_DELIVERY
        # No delivery in the same timestep, even at the pickup's own cell: LoRR checks
        # one errand per robot and timestep, so such a task ends a timestep later (the
        # robot kept there), never in zero time.
        self._set_goal(robot, int(self.delivery[robot]))

    def _delivered(self, robot: int) -> None:
        task, rec = int(self.task[robot]), self.rec
        self.delivered_at[task] = self.t
        rec.task_finished[task] = self.t
        rec.robot_free_at[robot] = self.t
        self.phase[robot] = _IDLE
        self.task[robot] = -1
        self._set_goal(robot, -1)
        heapq.heappush(self.free, robot)

    def _step(self) -> int:
        """One timestep for the whole fleet; returns how many goals were reached."""
        busy = self.phase != _IDLE
        self._move(busy)
        self.t += 1
        if self.record:
            self.trace.append(self.pos.astype(np.int32))
            if self.turns:
                self.heading_trace.append(self.heading.astype(np.int8))
        self.since[busy] += 1
        self._progress(busy)
        self.max_stall = max(self.max_stall, int(self.since.max(initial=0)))
        arrived = np.flatnonzero(busy & (self.pos == self.goal))
        for robot in arrived.tolist():
            if self.phase[robot] == _TO_PICKUP:
                self._picked_up(robot)
            else:
                self._delivered(robot)
        if self.guidance > 0:
            self._guide_update()
        return len(arrived)

    def _move(self, busy: np.ndarray) -> None:
        """Plan and take one timestep's moves (``pos``, ``heading``, ``action``)."""
        m = self.num_robots
        # Waiting longest first; idle robots last; ties: the lower id.
        # A robot with a goal in a dead end gains 10 a timestep there (the kit's PIBT):
        # it must back out before the robots queued behind it can move.
        self.boost[busy & self._dead_end[self.pos]] += _DEAD_END_BONUS
        prio = (self.since + self.boost).astype(np.float64)
        stuck = busy & (self.stuck >= (self.patience or 1 << 62))
        if stuck.any():
            # Priority rotation: a fixed order can hold two robots in a standoff forever.
            prio[stuck] = self.rng.random(int(stuck.sum())) * (prio.max() + 1.0)
            self.rotations += 1
        # lexsort((ids, ~busy, -prio)), as one stable sort of busy-then-idle robots.
        first = np.concatenate([np.flatnonzero(busy), np.flatnonzero(~busy)])
        order = first[np.argsort(-prio[first], kind="stable")]
        tie = self.rng.random((m, 5))
        if self.guidance > 0:
            self.guides.ties(self.pos, tie)
        if self.turns:
            turn_step(
                self.pos, self.heading, self.target, order, self.goal_field, self.fields.store,
                self.nbr, tie, self.occ_now, self.occ_next, self.nxt, self.action,
            )  # fmt: skip
            turned = (self.action != FORWARD) & (self.action != WAIT)
            self.turn_actions += int(np.count_nonzero(turned))
        else:
            pibt_step(
                self.pos, order, self.goal_field, self.fields.store, self.nbr, tie,
                self.occ_now, self.occ_next, self.nxt,
            )  # fmt: skip

    def _guide_update(self) -> None:
        """Advance the guide paths after a timestep; plan the needed ones."""
        self.guides.update(self.pos, self.goal, self.goal_field, self.fields.store, self.t)

    def _progress(self, busy: np.ndarray) -> None:
        """Count, per busy robot, the timesteps since it last got nearer its goal."""
        robots = np.flatnonzero(busy)
        d = self.fields.store[self.goal_field[robots], self.pos[robots]].astype(np.int64)
        nearer = d < self.best[robots]
        self.best[robots] = np.minimum(self.best[robots], d)
        self.stuck[robots] = np.where(nearer, 0, self.stuck[robots] + 1)

    def schedule(self) -> Schedule:
        if not self._done:
            raise InvalidActionError("the schedule is complete only when the episode is done")
        if not self.record:
            raise ConfigError("navigator.record=false: this pibt episode kept no positions")
        served = np.flatnonzero(self.delivered_at >= 0)
        headings = np.stack(self.heading_trace).astype(np.int64) if self.turns else None
        return Schedule.of_tasks(
            self.cells[np.stack(self.trace)], self.rec, served, self.pickup_at,
            self.delivered_at, headings,
        )  # fmt: skip

    def stats(self) -> dict[str, float]:
        """``timesteps``, ``field_searches`` (BFS fields computed), ``max_stall`` (the
        most timesteps a robot waited for its goal to change), ``rotations`` (timesteps
        with a priority rotation) and, with ``turns``, ``turn_actions`` (quarter turns
        taken, all robots)."""
        out = {
            "timesteps": float(self.t),
            "field_searches": float(self.fields.searches),
            "max_stall": float(self.max_stall),
            "rotations": float(self.rotations),
        }
        if self.turns:
            out["turn_actions"] = float(self.turn_actions)
        if self.guidance > 0:
            out["guide_paths"] = float(self.guides.planned)
        if self.released:
            out["reassigned"] = float(self.released)
        if self.deferred:
            out["deferred"] = float(self.deferred)
        return out
