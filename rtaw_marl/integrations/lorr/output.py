"""LoRR's output format, both ways: the project's episodes out, any output replayed.

:func:`episode_output` writes an executed episode (a :class:`~rtaw_marl.sim.mapf.schedule.Schedule`
of ``navigator=pibt``, ``sipp`` or ``cbs``) as the JSON ``lifelong`` writes, so that
LoRR's viewer PlanViz replays it: ``actualPaths``, ``events``, ``tasks``, ``start``,
``actualSchedule``. Robots here move in four directions without turning, so the action
model is PlanViz's ``MAPF`` (no headings), with its letters: ``R`` one column right,
``L`` left, ``U`` one row down (row + 1), ``D`` one row up, ``W`` wait. Tasks are numbered
in the schedule's order; an event is ``[timestep, robot, task, errands reached]``.

:func:`replay` reads such a file, ``lifelong``'s own (``MAPF_T``: ``F`` forward, ``R``
clockwise, ``C`` counter-clockwise, ``W``/``T`` wait; headings ``E, S, W, N`` move
``+col, +row, -col, -row``) or ours, and checks it on its own code path: every cell
free, no two robots in a cell or swapping, every event at its errand's cell and in
order, and counts the tasks finished. The start kit's evaluation mode (``lifelong -m``)
is declared by v2.1.2 but not implemented, so this is the round trip: LoRR's outputs
replay to their own ``numTaskFinished``; ours to the episode they came from.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from rtaw_marl.errors import ConfigError
from rtaw_marl.sim.layout import Layout
from rtaw_marl.sim.mapf.schedule import Schedule
from rtaw_marl.utils.atomic import atomic_write

__all__ = [
    "Replay",
    "episode_output",
    "read_replay",
    "read_schedule",
    "replay",
    "write_episode",
]

#: PlanViz's ``MAPF`` letters: (row, column) change.
_MAPF_MOVES = {"U": (1, 0), "D": (-1, 0), "R": (0, 1), "L": (0, -1), "W": (0, 0), "T": (0, 0)}
#: LoRR's headings 0..3 = E, S, W, N: (row, column) change of a forward move.
_HEADINGS = np.array([[0, 1], [1, 0], [0, -1], [-1, 0]], dtype=np.int64)
_START_HEADING = {"E": 0, "S": 1, "W": 2, "N": 3}


def episode_output(schedule: Schedule, horizon: int | None = None) -> dict[str, Any]:
    """An executed episode as a LoRR output object (action model ``MAPF``).

    Args:
        schedule: The episode.
        horizon: Timesteps to write (default: the whole schedule); tasks delivered
            later are not finished in it.
    """
    pos = schedule.positions if horizon is None else schedule.positions[: int(horizon) + 1]
    steps = pos.shape[0] - 1
    rc = pos[..., ::-1]  # (row, col)
    delta = np.diff(rc, axis=0)  # [T, M, 2]
    letters = np.full(delta.shape[:2], "W", dtype="<U1")
    for letter, (dr, dc) in _MAPF_MOVES.items():
        if letter not in ("W", "T"):
            letters[(delta[..., 0] == dr) & (delta[..., 1] == dc)] = letter
    if (np.abs(delta).sum(axis=-1) > 1).any():
        raise ConfigError("the schedule moves a robot more than one cell in a timestep")
    paths = [",".join(letters[:, r]) for r in range(pos.shape[1])]
    tasks, events, plan = [], [], [[] for _ in range(pos.shape[1])]
    order = np.argsort(schedule.task_assigned, kind="stable")
    for tid, k in enumerate(order.tolist()):
        ox, oy, dx, dy = (int(v) for v in schedule.tasks[k])
        robot = int(schedule.task_robot[k])
        tasks.append([tid, int(schedule.task_arrival[k]), [oy, ox, dy, dx]])
        plan[robot].append(f"{int(schedule.task_assigned[k])}:{tid}")
        for seq, when in ((1, schedule.task_pickup[k]), (2, schedule.task_delivered[k])):
            if when <= steps:
                events.append([int(when), robot, tid, seq])
    events.sort()
    finished = sum(1 for e in events if e[3] == 2)
    return {
        "actionModel": "MAPF",
        "version": "2024 LoRR",
        "teamSize": int(pos.shape[1]),
        "start": [[int(r), int(c), "N/A"] for r, c in rc[0]],
        "numTaskFinished": finished,
        "makespan": steps,
        "numPlannerErrors": 0,
        "numScheduleErrors": 0,
        "numEntryTimeouts": 0,
        "actualPaths": paths,
        "plannerPaths": paths,
        "errors": [],
        "actualSchedule": [",".join(p) for p in plan],
        "plannerSchedule": [",".join(p) for p in plan],
        "scheduleErrors": [],
        "events": events,
        "tasks": tasks,
    }


def write_episode(schedule: Schedule, path: str | Path, horizon: int | None = None) -> Path:
    """:func:`episode_output` written atomically to ``path``."""
    text = json.dumps(episode_output(schedule, horizon))
    return atomic_write(path, lambda fh: fh.write(text.encode()))


@dataclass(frozen=True)
class Replay:
    """A LoRR output replayed.

    Attributes:
        positions: ``int64 [T + 1, M, 2]`` each robot's ``(row, col)`` at each timestep.
        tasks_finished: Tasks whose last errand was reached (from the events, checked).
        events_checked: Events found at their errand's cell, in order.
    """

    positions: np.ndarray
    tasks_finished: int
    events_checked: int


def read_replay(path: str | Path, layout: Layout) -> Replay:
    """:func:`replay` of a file."""
    try:
        data = json.loads(Path(path).read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:
        raise ConfigError(f"{path}: not a LoRR output file ({exc})") from None
    return replay(data, layout)


def read_schedule(path: str | Path, layout: Layout) -> Schedule:
    """A LoRR output file (``lifelong``'s or ``rtaw-render``'s) as a checked :class:`Schedule`.

    The file is replayed and checked first (:func:`replay`). Each task's robot and
    assignment time come from ``actualSchedule`` (the entry of the robot its events name,
    else the last), its pickup and delivery from its first and last errand's events; a
    task not yet picked up or delivered at the end has that time set to ``T + 1``.
    Tasks keep their ids' order. Tasks that were never assigned are left out.
    """
    try:
        data = json.loads(Path(path).read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:
        raise ConfigError(f"{path}: not a LoRR output file ({exc})") from None
    played = replay(data, layout)
    end = played.positions.shape[0]  # T + 1: "not within the episode"
    errands = {int(t[0]): np.asarray(t[2], dtype=np.int64).reshape(-1, 2) for t in data["tasks"]}
    release = {int(t[0]): int(t[1]) for t in data["tasks"]}
    reached: dict[int, dict[int, int]] = {}
    by_events: dict[int, int] = {}
    for t, robot, task, seq in (tuple(int(v) for v in e[:4]) for e in data["events"]):
        reached.setdefault(task, {})[seq] = t
        by_events.setdefault(task, robot)
    assigned: dict[int, tuple[int, int]] = {}
    for robot, text in enumerate(data.get("actualSchedule", [])):
        for entry in filter(None, str(text).split(",")):
            when, _, task = entry.partition(":")
            tid = int(task)
            if tid in errands and by_events.get(tid, robot) == robot:
                assigned[tid] = (robot, int(when))
    ids = sorted(assigned)
    rows = np.array(
        [[*errands[k][0, ::-1], *errands[k][-1, ::-1]] for k in ids], dtype=np.int64
    ).reshape(-1, 4)
    return Schedule(
        positions=played.positions[..., ::-1].copy(),
        tasks=rows,
        task_robot=np.array([assigned[k][0] for k in ids], dtype=np.int64),
        task_arrival=np.array([release[k] for k in ids], dtype=np.int64),
        task_assigned=np.array([assigned[k][1] for k in ids], dtype=np.int64),
        task_pickup=np.array([reached.get(k, {}).get(1, end) for k in ids], dtype=np.int64),
        task_delivered=np.array(
            [reached.get(k, {}).get(len(errands[k]), end) for k in ids], dtype=np.int64
        ),
    )


def replay(data: dict[str, Any], layout: Layout) -> Replay:
    """Replay and check a LoRR output object on ``layout``.

    Raises:
        ConfigError: A key is missing, an action unknown, a robot leaves the free cells,
            two robots share a cell or swap, or an event is not at its errand (the
            message says which robot, task and timestep).
    """
    try:
        model = data["actionModel"]
        starts = data["start"]
        actions = [str(p).split(",") if p else [] for p in data["actualPaths"]]
        events, tasks = data["events"], data["tasks"]
    except (KeyError, TypeError) as exc:
        raise ConfigError(f"not a LoRR output object: missing {exc}") from None
    if len({len(a) for a in actions}) > 1:
        raise ConfigError("actualPaths have different lengths")
    codes = np.array(actions, dtype="<U1").reshape(len(actions), -1).T  # [T, M]
    rc0 = np.array([[int(s[0]), int(s[1])] for s in starts], dtype=np.int64)
    if model == "MAPF":
        delta = _mapf_deltas(codes)
    elif model == "MAPF_T":
        heading0 = np.array([_START_HEADING.get(str(s[2]), 0) for s in starts], dtype=np.int64)
        delta = _turning_deltas(codes, heading0)
    else:
        raise ConfigError(f"unknown actionModel {model!r}; valid: MAPF, MAPF_T")
    positions = np.concatenate([rc0[None], rc0[None] + np.cumsum(delta, axis=0)])
    _check_cells(positions, layout)
    _check_conflicts(positions)
    finished, checked = _check_events(positions, events, tasks)
    return Replay(positions, finished, checked)


def _mapf_deltas(codes: np.ndarray) -> np.ndarray:
    delta = np.zeros((*codes.shape, 2), dtype=np.int64)
    known = np.isin(codes, list(_MAPF_MOVES))
    if not known.all():
        t, r = np.argwhere(~known)[0]
        raise ConfigError(f"robot {r}: unknown MAPF action {str(codes[t, r])!r} at timestep {t}")
    for letter, move in _MAPF_MOVES.items():
        delta[codes == letter] = move
    return delta


def _turning_deltas(codes: np.ndarray, heading0: np.ndarray) -> np.ndarray:
    known = np.isin(codes, ["F", "R", "C", "W", "T"])
    if not known.all():
        t, r = np.argwhere(~known)[0]
        raise ConfigError(f"robot {r}: unknown MAPF_T action {str(codes[t, r])!r} at timestep {t}")
    turn = (codes == "R").astype(np.int64) - (codes == "C")
    # The heading during timestep t: the start's, turned by every action before t.
    before = np.concatenate([np.zeros((1, codes.shape[1]), np.int64), np.cumsum(turn, 0)[:-1]])
    heading = (heading0[None] + before) % 4
    return _HEADINGS[heading] * (codes == "F")[..., None]


def _check_cells(positions: np.ndarray, layout: Layout) -> None:
    rows, cols = positions[..., 0], positions[..., 1]
    inside = (rows >= 0) & (rows < layout.height) & (cols >= 0) & (cols < layout.width)
    free = np.zeros_like(inside)
    free[inside] = ~layout.obstacles[rows[inside], cols[inside]]
    if not free.all():
        t, r = np.argwhere(~free)[0]
        raise ConfigError(
            f"robot {r} is on a blocked or outside cell {tuple(positions[t, r].tolist())} at "
            f"timestep {t}"
        )


def _check_conflicts(positions: np.ndarray) -> None:
    cell = positions[..., 0] * (positions[..., 1].max() + 2) + positions[..., 1]
    order = np.sort(cell, axis=1)
    same = order[:, 1:] == order[:, :-1]
    if same.any():
        t = int(np.argwhere(same)[0][0])
        robots = np.flatnonzero(np.isin(cell[t], order[t, 1:][same[t]]))
        raise ConfigError(f"robots {robots[0]} and {robots[1]} share a cell at timestep {t}")
    # A swap: robots a and b trade cells between t and t + 1 (edge a->b and b->a).
    t, robot = np.nonzero(cell[:-1] != cell[1:])
    size = int(cell.max()) + 1
    src, dst = cell[t, robot], cell[t + 1, robot]
    edge = (t * size + src) * size + dst
    back = np.isin((t * size + dst) * size + src, edge)
    if back.any():
        i = int(np.flatnonzero(back)[0])
        other = np.flatnonzero((t == t[i]) & (src == dst[i]) & (dst == src[i]))[0]
        raise ConfigError(f"robots {robot[i]} and {robot[other]} swap cells at timestep {t[i] + 1}")


def _check_events(positions: np.ndarray, events: list[Any], tasks: list[Any]) -> tuple[int, int]:
    errands = {int(t[0]): np.asarray(t[2], dtype=np.int64).reshape(-1, 2) for t in tasks}
    reached: dict[int, int] = {}
    finished = 0
    for t, robot, task, seq in (tuple(int(v) for v in e[:4]) for e in events):
        if task not in errands or not 1 <= seq <= len(errands[task]):
            raise ConfigError(f"event at timestep {t}: task {task} has no errand {seq}")
        if reached.get(task, 0) != seq - 1:
            raise ConfigError(f"event at timestep {t}: task {task} errand {seq} out of order")
        if t >= len(positions) or not np.array_equal(positions[t, robot], errands[task][seq - 1]):
            raise ConfigError(
                f"event at timestep {t}: robot {robot} is not at errand {seq} of task {task}"
            )
        reached[task] = seq
        finished += seq == len(errands[task])
    return finished, len(events)
