"""The simulator's parameters (:class:`SimConfig`, the ``sim.*`` keys) and the arrays it
keeps its state in (:class:`SimBuffers`)."""

from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np

from rtaw_marl.errors import ConfigError
from rtaw_marl.sim.layout import MAX_COORDINATE
from rtaw_marl.utils.checks import at_least, check_fields, check_number

__all__ = ["EPISODE_MODES", "REFILLS", "REWARDS", "SimBuffers", "SimConfig"]

EPISODE_MODES = ("drain", "paper", "horizon")
#: When an emptied queue slot takes the next task of the stream.
REFILLS = ("assign", "finish")
#: Reward = minus this quantity of the chosen task (the paper's reward ablation, then
#: ``pair_cost``: the 2024 LoRR winner's pair cost per cell of travel to the pickup).
REWARDS = ("ttd", "length", "ttd_length", "pair_cost")
#: The 2024 LoRR winner's weight of the travel to a task's pickup against the task's
#: length (``Straple/OMAPFS``, ``greedy_scheduler.cpp``): its pair cost is
#: ``PAIR_WEIGHT x travel + length``.
PAIR_WEIGHT = 5.0


@dataclass(frozen=True)
class SimConfig:
    """Parameters of the simulator (the ``sim.*`` config keys).

    Attributes:
        num_robots: ``M``, at least 1.
        num_tasks: Tasks served (``drain``) or decisions taken (``paper``) per episode;
            with ``horizon``, the most tasks the stream holds (the episode ends sooner
            if they are all assigned; with ``reassign`` a task given back and taken
            again is counted once).
        queue_len: ``N``, the number of visible queued tasks, at least 1.
        episode_mode: ``"drain"``, ``"paper"`` or ``"horizon"``: decisions until the
            timestep ``horizon`` (throughput: the tasks finished by then).
        horizon: The last timestep of a ``horizon`` episode (required there, unused
            otherwise).
        refill: ``"assign"`` (default): a slot takes the next task when its task is
            assigned, so the queue always shows ``N`` unassigned tasks. ``"finish"``:
            when its task is finished (LoRR's reveal window: ``N`` counts the tasks
            revealed and not finished, assigned ones included); the freed robot's
            slot is refilled just before its next decision. Needs ``N > M``.
        reassign: LoRR's reassignment (needs ``refill=finish`` and ``navigator=pibt``):
            a task stays in its slot, *held* by its robot, until the robot reaches its
            pickup, and a free robot may take a held task (the holder is then free
            where it stands, at once); a task changes hands at most once per timestep.
            Rules that do not use it choose among the unassigned tasks as before.
        decision_budget: Most decisions per timestep (``navigator=pibt``); the free
            robots not served by then wait for the next timestep, as LoRR's clock
            defers them (counted as ``deferred`` in the executor's stats). The
            deterministic budget, for training and tests; ``None``: no limit.
        time_budget_ms: Wall-clock milliseconds the policy may spend per timestep
            (``navigator=pibt``), measured between each decision's start and its
            action; past it the free robots wait as above. For judging (LoRR gives the
            scheduler half of ``planTimeLimit``: 500); not reproducible run to run.
        noise_mean: Mean of the Gaussian noise added to completion times (seconds),
            at least 0: a delay on top of the travel time (single draws below 0 end a
            task no earlier than its decision).
        noise_var: Its variance, at least 0; 0 makes the dynamics deterministic.
        reward: ``"ttd"`` (default), ``"length"``, ``"ttd_length"`` or ``"pair_cost"``
            (``ttd + length / PAIR_WEIGHT``: the winner's pair cost in cells of travel,
            the delivery leg a tie-breaker between tasks equally near).
        robot_starts: ``(x, y)`` start cell per robot; random distinct free cells from
            the episode seed when ``None``.
        robot_free_times: Time at which each robot is first free; all 0 when ``None``.
    """

    num_robots: int = 10
    num_tasks: int = 500
    queue_len: int = 10
    episode_mode: str = "drain"
    horizon: int | None = None
    refill: str = "assign"
    reassign: bool = False
    decision_budget: int | None = None
    time_budget_ms: float | None = None
    noise_mean: float = 0.25
    noise_var: float = 0.25
    reward: str = "ttd"
    robot_starts: list[list[int]] | None = None
    robot_free_times: list[float] | None = None

    def __post_init__(self) -> None:
        check_fields(self, "sim.")
        at_least(self, "sim.", 1, "num_robots", "num_tasks", "queue_len")
        if self.episode_mode not in EPISODE_MODES:
            raise ConfigError(
                f"sim.episode_mode must be one of {', '.join(EPISODE_MODES)}, "
                f"got {self.episode_mode!r}"
            )
        if self.refill not in REFILLS:
            raise ConfigError(
                f"sim.refill must be one of {', '.join(REFILLS)}, got {self.refill!r}"
            )
        if self.episode_mode == "horizon" and self.horizon is None:
            raise ConfigError("sim.episode_mode=horizon needs sim.horizon=T (timesteps)")
        if self.horizon is not None:
            at_least(self, "sim.", 1, "horizon")
        if self.refill == "finish" and self.queue_len <= self.num_robots:
            raise ConfigError(
                f"sim.refill=finish needs sim.queue_len > sim.num_robots (the revealed "
                f"tasks include the M in progress), got {self.queue_len} <= {self.num_robots}"
            )
        if not isinstance(self.reassign, bool):
            raise ConfigError(f"sim.reassign must be true or false, got {self.reassign!r}")
        if self.reassign and self.refill != "finish":
            raise ConfigError(
                "sim.reassign=true needs sim.refill=finish (LoRR's reveal window: a held "
                "task keeps its slot until it is picked up)"
            )
        if self.decision_budget is not None:
            at_least(self, "sim.", 1, "decision_budget")
        if self.time_budget_ms is not None:
            check_number("sim.time_budget_ms", self.time_budget_ms, minimum=0)
        if self.reward not in REWARDS:
            raise ConfigError(
                f"sim.reward must be one of {', '.join(REWARDS)}, got {self.reward!r}"
            )
        check_number("sim.noise_var", self.noise_var, minimum=0)
        # The noise is a delay on top of the shortest travel time: a robot cannot beat
        # its shortest path on average, and a negative mean would end tasks at their
        # decision time (a makespan of 0 for noise_mean=-100).
        check_number("sim.noise_mean", self.noise_mean, minimum=0)
        if self.robot_starts is not None:
            starts = tuple(tuple(s) for s in self.robot_starts)
            if len(starts) != self.num_robots or any(len(s) != 2 for s in starts):
                raise ConfigError(
                    f"sim.robot_starts must hold num_robots={self.num_robots} [x, y] pairs, "
                    f"got {len(starts)} entries"
                )
            far = [v for s in starts for v in s if abs(v) > MAX_COORDINATE]
            if far:
                raise ConfigError(f"sim.robot_starts: coordinate {far[0]} is out of range")
            object.__setattr__(self, "robot_starts", starts)
        if self.robot_free_times is not None:
            times = tuple(float(t) for t in self.robot_free_times)
            if len(times) != self.num_robots or not all(t >= 0 for t in times):
                raise ConfigError(
                    f"sim.robot_free_times must hold num_robots={self.num_robots} finite "
                    "non-negative times"
                )
            object.__setattr__(self, "robot_free_times", times)


@dataclass(frozen=True)
class SimBuffers:
    """Arrays a simulator keeps its state in, overwritten in place at every reset and step.

    A batched env passes views into ``[B, ...]`` arrays here, so features of all ``B``
    simulators are computed with one vectorised expression.

    Attributes:
        robot_xy: ``int64 [M, 2]`` cell of each robot when next free.
        robot_free_at: ``float64 [M]`` time each robot becomes free.
        queue_mask: ``bool [N]`` which slots hold a task.
        queue_rows: ``int64 [N, 4]`` ``(ox, oy, dx, dy)`` per slot, zeros when empty.
        queue_length: ``float64 [N]`` task length per slot, 0 when empty.
    """

    robot_xy: np.ndarray
    robot_free_at: np.ndarray
    queue_mask: np.ndarray
    queue_rows: np.ndarray
    queue_length: np.ndarray

    @classmethod
    def allocate(cls, num_robots: int, queue_len: int) -> SimBuffers:
        """Fresh buffers for ``num_robots`` robots and ``queue_len`` slots."""
        return cls(
            robot_xy=np.zeros((num_robots, 2), dtype=np.int64),
            robot_free_at=np.zeros(num_robots, dtype=np.float64),
            queue_mask=np.zeros(queue_len, dtype=bool),
            queue_rows=np.zeros((queue_len, 4), dtype=np.int64),
            queue_length=np.zeros(queue_len, dtype=np.float64),
        )

    def check(self, num_robots: int, queue_len: int) -> None:
        """Raise ConfigError unless shapes and dtypes fit ``num_robots`` and ``queue_len``."""
        expected = SimBuffers.allocate(num_robots, queue_len)
        for f in fields(self):
            got, want = getattr(self, f.name), getattr(expected, f.name)
            if got.shape != want.shape or got.dtype != want.dtype:
                raise ConfigError(
                    f"buffer {f.name} must be {want.dtype} {want.shape}, "
                    f"got {got.dtype} {got.shape}"
                )
