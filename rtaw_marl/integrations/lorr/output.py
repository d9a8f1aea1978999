"""LoRR's output format, both ways: the project's episodes out, any output replayed.

:func:`episode_output` writes an executed episode (a :class:`~rtaw_marl.sim.mapf.schedule.Schedule`
of ``navigator=pibt``, ``sipp`` or ``cbs``) as the JSON ``lifelong`` writes, so that
LoRR's viewer PlanViz replays it: ``actualPaths``, ``events``, ``tasks``, ``start``,
``actualSchedule``. Robots here move in four directions without turning, so the action
model is PlanViz's ``MAPF`` (no headings), with its letters: ``R`` one column right,
``L`` left, ``U`` one row down (row + 1), ``D`` one row up, ``W`` wait. A task's id is its
index in the episode's task stream (``Schedule.task_ids``: for a LoRR problem, the id
LoRR's ``lifelong`` gives the same task), so ids of tasks never assigned are missing; a
schedule without stream ids numbers its tasks by assignment order. An event is
``[timestep, robot, task, errands reached]``.

:func:`replay` reads such a file, ``lifelong``'s own (``MAPF_T``: ``F`` forward, ``R``
clockwise, ``C`` counter-clockwise, ``W``/``T`` wait; headings ``E, S, W, N`` move
``+col, +row, -col, -row``) or ours, through the one reader of the format
(:mod:`rtaw_marl.viz.schedule_file`, which rtaw-view uses too): every field checked,
every cell free, no two robots in a cell or swapping, every event at its errand's cell
and in order, and the tasks finished counted. The start kit's evaluation mode
(``lifelong -m``) is declared by v2.1.2 but not implemented, so this is the round trip:
LoRR's outputs replay to their own ``numTaskFinished``; ours to the episode they came
from.
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
from rtaw_marl.viz.schedule_fields import HEADINGS, NO_HEADING
from rtaw_marl.viz.schedule_file import SavedEpisode, read_schedule_data, read_schedule_file

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


def episode_output(schedule: Schedule, horizon: int | None = None) -> dict[str, Any]:
    """An executed episode as a LoRR output object (action model ``MAPF_T`` when its
    robots turn, else ``MAPF``).

    Args:
        schedule: The episode.
        horizon: Timesteps to write (default: the whole schedule); tasks delivered
            later are not finished in it.
    """
    end = None if horizon is None else int(horizon) + 1
    pos = schedule.positions[:end]
    steps = pos.shape[0] - 1
    rc = pos[..., ::-1]  # (row, col)
    delta = np.diff(rc, axis=0)  # [T, M, 2]
    if (np.abs(delta).sum(axis=-1) > 1).any():
        raise ConfigError("the schedule moves a robot more than one cell in a timestep")
    if schedule.headings is None:
        model, letters = "MAPF", _mapf_letters(delta)
        start = [[int(r), int(c), NO_HEADING] for r, c in rc[0]]
    else:
        heading = np.asarray(schedule.headings)[:end]
        model, letters = "MAPF_T", _mapf_t_letters(delta, heading)
        start = [[int(r), int(c), HEADINGS[h]] for (r, c), h in zip(rc[0], heading[0], strict=True)]
    paths = [",".join(letters[:, r]) for r in range(pos.shape[1])]
    tasks, events, plan = [], [], [[] for _ in range(pos.shape[1])]
    order = np.argsort(schedule.task_assigned, kind="stable")
    ids = np.arange(len(order)) if schedule.task_ids is None else schedule.task_ids[order]
    for k, tid in zip(order.tolist(), ids.tolist(), strict=True):
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
        "actionModel": model,
        "version": "2024 LoRR",
        "teamSize": int(pos.shape[1]),
        "start": start,
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


def _mapf_letters(delta: np.ndarray) -> np.ndarray:
    """``MAPF`` letters ``[T, M]`` of the moves ``delta [T, M, 2]`` (row, column)."""
    letters = np.full(delta.shape[:2], "W", dtype="<U1")
    for letter, (dr, dc) in _MAPF_MOVES.items():
        if letter not in ("W", "T"):
            letters[(delta[..., 0] == dr) & (delta[..., 1] == dc)] = letter
    return letters


def _mapf_t_letters(delta: np.ndarray, heading: np.ndarray) -> np.ndarray:
    """``MAPF_T`` letters ``[T, M]``: ``F`` where a robot moved, ``R`` / ``C`` where its
    heading ``[T + 1, M]`` turned a quarter clockwise / counter-clockwise, else ``W``."""
    turn = (heading[1:] - heading[:-1]) % 4
    letters = np.full(delta.shape[:2], "W", dtype="<U1")
    letters[turn == 1] = "R"
    letters[turn == 3] = "C"
    letters[np.abs(delta).sum(axis=-1) == 1] = "F"
    return letters


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
        tasks_assigned: Tasks assigned in ``actualSchedule`` (checked against events).
    """

    positions: np.ndarray
    tasks_finished: int
    tasks_assigned: int


def read_replay(path: str | Path, layout: Layout) -> Replay:
    """:func:`replay` of a file (:func:`~rtaw_marl.viz.schedule_file.read_schedule_file`)."""
    return _replay(read_schedule_file(path, layout))


def read_schedule(path: str | Path, layout: Layout) -> Schedule:
    """A LoRR output file (``lifelong``'s or ``rtaw-render``'s) as a checked :class:`Schedule`.

    The file is checked in full and replayed by the one reader of the format,
    :func:`~rtaw_marl.viz.schedule_file.read_schedule_file` (what rtaw-view shows). Each
    task's robot and assignment time come from ``actualSchedule``, its pickup and
    delivery from its first and last errand's events; a task not yet picked up or
    delivered at the end has that time set to ``T + 1``. Tasks keep their ids' order.
    Tasks that were never assigned are left out.
    """
    return read_schedule_file(path, layout).schedule


def replay(data: dict[str, Any], layout: Layout) -> Replay:
    """Check and replay a LoRR output object on ``layout`` (the one reader of the
    format, :func:`~rtaw_marl.viz.schedule_file.read_schedule_data`).

    Raises:
        ConfigError: A key is missing or malformed, an action unknown, a robot leaves
            the free cells, two robots share a cell or swap, or an event is not at its
            errand (the message says which robot, task and timestep).
    """
    return _replay(read_schedule_data(data, layout, "(LoRR output)"))


def _replay(saved: SavedEpisode) -> Replay:
    positions = saved.schedule.positions[..., ::-1].copy()  # (x, y) -> (row, col)
    return Replay(positions, saved.tasks_finished, len(saved.schedule.tasks))
