"""A saved episode (a LoRR output file) read, checked in full, and replayed for the viewer.

:func:`read_schedule_file` is the one reader ``rtaw-view schedule=`` uses. It reads the
JSON, checks every field (:mod:`rtaw_marl.viz.schedule_fields`: types, ranges,
references, order), then replays the actions on the configured map and checks what the
episode does: every robot on a free cell at every timestep, no two robots in a cell or
swapping, every event at its errand's cell. Only then does it build the
:class:`~rtaw_marl.sim.mapf.schedule.Schedule` the viewer draws. Every problem is one
:class:`ScheduleFileError` line that starts ``schedule <file>:`` and names the entry.

LoRR's turning model (``MAPF_T``: ``F`` forward, ``R`` clockwise, ``C``
counter-clockwise, ``W``/``T`` wait; headings ``E, S, W, N`` move ``+col, +row, -col,
-row``) and ``rtaw-render``'s ``MAPF`` (``U`` row + 1, ``D`` row - 1, ``R`` column + 1,
``L`` column - 1) are both read.
"""

from __future__ import annotations

import bisect
import json
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from rtaw_marl.errors import ConfigError
from rtaw_marl.sim.layout import Layout
from rtaw_marl.sim.mapf.schedule import Schedule
from rtaw_marl.viz.schedule_fields import ScheduleFields, parse_fields

__all__ = ["SavedEpisode", "ScheduleFileError", "read_schedule_data", "read_schedule_file"]

#: ``MAPF`` letters: (row, column) change.
_MAPF_MOVES = {"U": (1, 0), "D": (-1, 0), "R": (0, 1), "L": (0, -1)}
#: A forward move of heading 0..3 (E, S, W, N): (row, column) change.
_FORWARD = np.array([[0, 1], [1, 0], [0, -1], [-1, 0]], dtype=np.int64)


class ScheduleFileError(ConfigError):
    """A saved episode that cannot be shown: one line, ``schedule <file>: <problem>``."""


@dataclass(frozen=True)
class SavedEpisode:
    """A saved episode, checked.

    Attributes:
        schedule: The episode as the viewer draws it (cells ``(x, y)``; a task's robot
            and assignment from ``actualSchedule``, its pickup and delivery from its
            first and last errand's events, ``T + 1`` when not reached; its
            ``task_ids`` the file's task ids).
        tasks_finished: Tasks whose last errand was reached.
    """

    schedule: Schedule
    tasks_finished: int


def read_schedule_file(
    path: str | Path,
    layout: Layout,
    budget: Callable[[int, int], None] | None = None,
) -> SavedEpisode:
    """Read, check and replay a LoRR output file on ``layout``.

    Args:
        path: The file (named in every message as given).
        layout: The map its cells are on.
        budget: Called with ``(robots, timesteps)`` once the fields are checked and
            before the episode is replayed (what grows with them); it may refuse.

    Raises:
        ScheduleFileError: The file cannot be read, is not JSON (or is nested too deep
            to parse), or a field, a move or an event is wrong.
    """
    try:
        data = _load(Path(path))
    except ConfigError as exc:
        raise ScheduleFileError(f"schedule {path}: {exc}") from None
    return read_schedule_data(data, layout, str(path), budget)


def read_schedule_data(
    data: object,
    layout: Layout,
    name: str = "(data)",
    budget: Callable[[int, int], None] | None = None,
) -> SavedEpisode:
    """Check and replay a LoRR output object (a file's JSON value) on ``layout``: the one
    check of the format, for files and objects alike.

    Args:
        data: The JSON value.
        layout: The map its cells are on.
        name: How messages name it (``schedule <name>: ...``).
        budget: As :func:`read_schedule_file`'s.

    Raises:
        ScheduleFileError: A field, a move or an event is wrong.
    """
    try:
        fields = parse_fields(data, layout)
        if budget is not None:
            budget(fields.num_robots, fields.horizon)
        rc = _positions(fields)
        _check_cells(rc, layout)
        _check_conflicts(rc)
        _check_events(rc, fields)
        chosen = _chosen(fields)
    except ScheduleFileError:
        raise
    except ConfigError as exc:
        raise ScheduleFileError(f"schedule {name}: {exc}") from None
    return _saved(fields, rc, chosen)


def _load(path: Path) -> object:
    """The file's JSON value."""
    try:
        raw = path.read_bytes()
    except OSError as exc:
        raise ConfigError(f"cannot be read ({exc.strerror or type(exc).__name__})") from None
    try:
        return json.loads(raw)
    except RecursionError:
        # The parser recurses per level: a file nested a few thousand deep (no LoRR
        # output is more than 3) would otherwise end in a traceback.
        raise ConfigError("is nested too deeply to be a LoRR output file") from None
    except ValueError as exc:  # JSONDecodeError, bad UTF-8, an integer of 5,000 digits
        first = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise ConfigError(f"is not a LoRR output file (not JSON: {first})") from None


def _positions(fields: ScheduleFields) -> np.ndarray:
    """``int64 [T + 1, M, 2]`` every robot's ``(row, column)`` at every timestep."""
    codes = fields.actions
    heading = _headings(fields)
    if heading is None:
        delta = np.zeros((*codes.shape, 2), dtype=np.int64)
        for letter, move in _MAPF_MOVES.items():
            delta[codes == ord(letter)] = move
    else:  # a forward move goes the way the robot faces during its timestep
        delta = _FORWARD[heading[:-1]] * (codes == ord("F"))[..., None]
    return np.concatenate([fields.start[None], fields.start[None] + np.cumsum(delta, axis=0)])


def _headings(fields: ScheduleFields) -> np.ndarray | None:
    """``int64 [T + 1, M]`` every robot's heading at every timestep (``MAPF_T``: the
    start's, turned by every action before), ``None`` for ``MAPF``."""
    if fields.action_model == "MAPF":
        return None
    codes = fields.actions
    turn = (codes == ord("R")).astype(np.int64) - (codes == ord("C"))
    before = np.concatenate([np.zeros((1, codes.shape[1]), np.int64), np.cumsum(turn, 0)])
    return (fields.heading[None] + before) % 4


def _check_cells(rc: np.ndarray, layout: Layout) -> None:
    """Every robot on a free cell of the map at every timestep."""
    rows, cols = rc[..., 0], rc[..., 1]
    inside = (rows >= 0) & (rows < layout.height) & (cols >= 0) & (cols < layout.width)
    free = np.zeros_like(inside)
    free[inside] = ~layout.obstacles[rows[inside], cols[inside]]
    if not free.all():
        t, r = (int(v) for v in np.argwhere(~free)[0])
        row, col = (int(v) for v in rc[t, r])
        where = "an obstacle" if inside[t, r] else f"outside the {layout.width}x{layout.height} map"
        raise ConfigError(f"robot {r} is at (row {row}, column {col}), {where}, at timestep {t}")


def _check_conflicts(rc: np.ndarray) -> None:
    """No two robots in one cell at a timestep, none trading cells between two."""
    cell = rc[..., 0] * (int(rc[..., 1].max()) + 2) + rc[..., 1]
    order = np.sort(cell, axis=1)
    same = order[:, 1:] == order[:, :-1]
    if same.any():
        t = int(np.argwhere(same)[0][0])
        a, b = (int(v) for v in np.flatnonzero(np.isin(cell[t], order[t, 1:][same[t]]))[:2])
        raise ConfigError(f"robots {a} and {b} share a cell at timestep {t}")
    # A swap: robots a and b trade cells between t and t + 1 (edge a->b and b->a).
    t, robot = np.nonzero(cell[:-1] != cell[1:])
    size = int(cell.max()) + 1
    src, dst = cell[t, robot], cell[t + 1, robot]
    edge = (t * size + src) * size + dst
    back = np.isin((t * size + dst) * size + src, edge)
    if back.any():
        i = int(np.flatnonzero(back)[0])
        other = int(np.flatnonzero((t == t[i]) & (src == dst[i]) & (dst == src[i]))[0])
        raise ConfigError(
            f"robots {int(robot[i])} and {int(robot[other])} swap cells at timestep {int(t[i]) + 1}"
        )


def _check_events(rc: np.ndarray, fields: ScheduleFields) -> None:
    """Every event's robot stands on its errand's cell at its timestep."""
    if not len(fields.events):
        return
    t, robot, task, seq = fields.events.T
    want = np.array(
        [fields.tasks[k][1][s - 1] for k, s in zip(task.tolist(), seq.tolist(), strict=True)]
    )
    away = (rc[t, robot] != want).any(axis=1)
    if away.any():
        i = int(np.argmax(away))
        row, col = (int(v) for v in rc[t[i], robot[i]])
        raise ConfigError(
            f"events[{i}]: robot {int(robot[i])} is at (row {row}, column {col}) at timestep "
            f"{int(t[i])}, not at errand {int(seq[i])} of task {int(task[i])} (row "
            f"{int(want[i, 0])}, column {int(want[i, 1])})"
        )


def _chosen(fields: ScheduleFields) -> dict[int, tuple[int, int]]:
    """Task id -> ``(robot, assignment timestep)`` of every assigned task.

    A task with events belongs to their robot, assigned by its last ``actualSchedule``
    entry for the task at or before the first event; any other task to its latest
    assignment (LoRR may hand an unopened task to another robot).

    Raises:
        ConfigError: A task's robot reaches it without an assignment before.
    """
    first: dict[int, tuple[int, int, int]] = {}  # task -> (timestep, robot, event index)
    for i, (t, robot, task, _) in enumerate(fields.events.tolist()):
        first.setdefault(task, (t, robot, i))
    chosen: dict[int, tuple[int, int]] = {}
    for robot, t, task in fields.assignments.tolist():
        if task == -1:
            continue
        if task in first:
            when, by, _ = first[task]
            if robot != by or t > when:
                continue
        if task not in chosen or t >= chosen[task][1]:
            chosen[task] = (robot, t)
    for task, (when, by, i) in first.items():
        if task not in chosen:
            raise ConfigError(
                f"events[{i}]: robot {by} reaches task {task} at timestep {when}, but "
                f"actualSchedule does not assign the task to robot {by} by then"
            )
    _check_held(fields, chosen)
    return chosen


def _check_held(fields: ScheduleFields, chosen: dict[int, tuple[int, int]]) -> None:
    """A robot reaches a task's errands while it holds the task: its ``actualSchedule``
    has no other entry after the assignment and before the task's last event (LoRR
    records every change of a robot's task; a finished task's robot may get the next
    one at the timestep of the delivery)."""
    times: dict[int, list[tuple[int, int]]] = {}  # robot -> its (timestep, task) entries
    for robot, t, task in fields.assignments.tolist():
        times.setdefault(robot, []).append((t, task))
    last: dict[int, tuple[int, int]] = {}  # task -> (timestep, event index) of its last
    for i, (t, _, task, _) in enumerate(fields.events.tolist()):
        last[task] = (t, i)
    for task, (end, i) in last.items():
        robot, start = chosen[task]
        entries = times[robot]
        k = bisect.bisect_right(entries, (start, task))
        if k < len(entries) and entries[k][0] < end:
            when, other = entries[k]
            took = "took its task away" if other == -1 else f"gave it task {other}"
            raise ConfigError(
                f"events[{i}]: robot {robot} reaches task {task} at timestep {end}, but "
                f"actualSchedule[{robot}] {took} at timestep {when}"
            )


def _saved(
    fields: ScheduleFields, rc: np.ndarray, chosen: dict[int, tuple[int, int]]
) -> SavedEpisode:
    """The checked episode as a :class:`Schedule` of its assigned tasks (``chosen``, in
    id order)."""
    end = fields.horizon + 1  # "not within the episode"
    reached: dict[int, dict[int, int]] = {}
    for t, _, task, seq in fields.events.tolist():
        reached.setdefault(task, {})[seq] = t
    ids = sorted(chosen)
    errands = [fields.tasks[k][1] for k in ids]
    rows = np.array([[*e[0, ::-1], *e[-1, ::-1]] for e in errands], dtype=np.int64)
    schedule = Schedule(
        positions=rc[..., ::-1].copy(),
        tasks=rows.reshape(-1, 4),
        task_robot=np.array([chosen[k][0] for k in ids], dtype=np.int64),
        task_arrival=np.array([fields.tasks[k][0] for k in ids], dtype=np.int64),
        task_assigned=np.array([chosen[k][1] for k in ids], dtype=np.int64),
        task_pickup=np.array([reached.get(k, {}).get(1, end) for k in ids], dtype=np.int64),
        task_delivered=np.array(
            [reached.get(k, {}).get(len(e), end) for k, e in zip(ids, errands, strict=True)],
            dtype=np.int64,
        ),
        headings=_headings(fields),
        task_ids=np.array(ids, dtype=np.int64),
    )
    finished = sum(1 for k, (_, e) in fields.tasks.items() if len(e) in reached.get(k, {}))
    return SavedEpisode(schedule, finished)
