"""The fields of a LoRR output file, each checked in full before anything uses them.

A saved episode (``rtaw-render output=*.json`` or LoRR's ``lifelong``) is JSON written
by another program, or edited by hand: every value is checked for its type, its range
and what it refers to, and the first problem is one line that names the key, the entry
and what is wrong (``start[3] heading 'Q' is not one of E, S, W, N``). Nothing is
guessed: an unknown heading is not read as east, a timestep of ``-1`` is not the last
one, a float is not truncated. What the episode *does* (robots on free cells, no
conflicts, events at their errands) is checked by :mod:`rtaw_marl.viz.schedule_file`.

The keys read (others, such as ``plannerPaths``, are ignored):

* ``actionModel``: ``MAPF`` (letters ``U D R L W T``) or ``MAPF_T`` (``F R C W T``);
* ``actualPaths``: per robot, its actions, comma-separated, one per timestep, all the
  same length (at least one);
* ``start``: per robot ``[row, column, heading]``, heading ``E, S, W, N`` (``N/A`` with
  ``MAPF``, where robots have none);
* ``tasks``: ``[id, release timestep, [row, column, row, column, ...]]``, its errands
  on free cells of the map;
* ``events``: ``[timestep, robot, task id, errand]`` (errand ``1..L``), a task's
  errands reached in order, in time, by one robot;
* ``actualSchedule``: per robot ``"timestep:task id,..."`` (``-1``: none), in time order;
* ``teamSize`` and ``numTaskFinished``, when present, must agree with the rest.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Any

import numpy as np

from rtaw_marl.errors import ConfigError
from rtaw_marl.sim.layout import Layout

__all__ = [
    "ACTIONS",
    "HEADINGS",
    "NO_HEADING",
    "REQUIRED",
    "ScheduleFields",
    "integer",
    "parse_fields",
    "show",
]

#: Action letters of each action model.
ACTIONS = {"MAPF": "UDRLWT", "MAPF_T": "FRCWT"}
#: LoRR's headings, numbered 0..3 as its simulator numbers them.
HEADINGS = ("E", "S", "W", "N")
#: The heading ``rtaw-render`` writes: its robots do not turn (``MAPF`` only).
NO_HEADING = "N/A"
#: The keys a LoRR output file must have.
REQUIRED = ("actionModel", "start", "actualPaths", "events", "tasks", "actualSchedule")

_NUMBER = re.compile(r"-1|[0-9]+", re.ASCII)


@dataclass(frozen=True)
class ScheduleFields:
    """A LoRR output file's fields, checked (see the module docstring).

    Attributes:
        action_model: ``"MAPF"`` or ``"MAPF_T"``.
        actions: ``uint8 [T, M]`` the ASCII action letter of robot ``m`` at timestep ``t``.
        start: ``int64 [M, 2]`` each robot's ``(row, column)`` at ``t = 0``.
        heading: ``int64 [M]`` its heading at ``t = 0`` (0..3 = E, S, W, N; -1: none).
        tasks: Task id -> ``(release timestep, int64 [L, 2] errands (row, column))``.
        events: ``int64 [E, 4]`` ``(timestep, robot, task id, errand)``.
        assignments: ``int64 [A, 3]`` ``(robot, timestep, task id)`` of ``actualSchedule``.
    """

    action_model: str
    actions: np.ndarray
    start: np.ndarray
    heading: np.ndarray
    tasks: dict[int, tuple[int, np.ndarray]]
    events: np.ndarray
    assignments: np.ndarray

    @property
    def num_robots(self) -> int:
        """``M``."""
        return int(self.actions.shape[1])

    @property
    def horizon(self) -> int:
        """``T``, the timesteps of ``actualPaths``."""
        return int(self.actions.shape[0])


def show(value: Any) -> str:
    """A JSON value as a message shows it: short, spelled as JSON spells it (a list or
    an object by its size: a file's value can be megabytes, or nested too deep to print)."""
    if isinstance(value, bool) or value is None:
        return {True: "true", False: "false", None: "null"}[value]
    if isinstance(value, str):
        return repr(value) if len(value) <= 40 else f"{value[:40]!r}..."
    if isinstance(value, int):
        text = str(value) if value.bit_length() < 100 else f"{str(value)[:20]}..."
        return text
    if isinstance(value, float):
        return repr(value)
    if isinstance(value, list):
        return f"a list of {_count(len(value), 'item', 'items')}"
    if isinstance(value, dict):
        return f"an object of {_count(len(value), 'key', 'keys')}"
    return type(value).__name__


def integer(value: Any, what: str, lo: int, hi: int | None = None) -> int:
    """``value`` if it is a JSON integer in ``lo .. hi - 1`` (no upper bound: ``None``).

    Raises:
        ConfigError: A float (``3.0``, ``NaN``), a string, ``true`` or an integer out of
            range, named by ``what``.
    """
    # type(...) is int: JSON's true and false are Python bools, a subclass of int.
    if type(value) is not int:
        raise ConfigError(f"{what} is {show(value)}, not an integer")
    if value < lo or (hi is not None and value >= hi):
        bound = f"at least {lo}" if hi is None else f"in {lo}..{hi - 1}"
        raise ConfigError(f"{what} is {show(value)}; it must be {bound}")
    return value


def parse_fields(data: Any, layout: Layout) -> ScheduleFields:
    """Check a parsed LoRR output file in full and return its fields.

    Raises:
        ConfigError: The first problem found, in one line naming the key and the entry.
    """
    if not isinstance(data, dict):
        raise ConfigError(f"holds {show(data)}, not a JSON object (a LoRR output file)")
    missing = [key for key in REQUIRED if key not in data]
    if missing:
        raise ConfigError(
            f"has no {missing[0]!r} key; a LoRR output file has {', '.join(REQUIRED)}"
        )
    model = data["actionModel"]
    if model not in ACTIONS:
        raise ConfigError(f"actionModel is {show(model)}, not one of {', '.join(ACTIONS)}")
    actions = _paths(data["actualPaths"], ACTIONS[model])
    steps, robots = actions.shape
    if "teamSize" in data:
        team = integer(data["teamSize"], "teamSize", 1)
        if team != robots:
            raise ConfigError(f"teamSize is {team} but actualPaths has {robots} robots")
    start, heading = _starts(data["start"], robots, model)
    tasks = _tasks(data["tasks"], layout)
    events = _events(data["events"], robots, steps, tasks)
    assignments = _assignments(data["actualSchedule"], robots, steps, tasks)
    fields = ScheduleFields(model, actions, start, heading, tasks, events, assignments)
    if "numTaskFinished" in data:
        said = integer(data["numTaskFinished"], "numTaskFinished", 0)
        done = sum(1 for _, task, seq in events[:, 1:].tolist() if seq == len(tasks[task][1]))
        if said != done:
            raise ConfigError(f"numTaskFinished is {said} but its events finish {done} tasks")
    return fields


def _count(n: int, one: str, many: str) -> str:
    """``"1 entry"``, ``"3 entries"``."""
    return f"{n} {one if n == 1 else many}"


def _list(value: Any, key: str) -> list[Any]:
    if not isinstance(value, list):
        raise ConfigError(f"{key} is {show(value)}, not a list")
    return value


def _paths(value: Any, letters: str) -> np.ndarray:
    """``actualPaths`` as ``uint8 [T, M]`` letters."""
    paths = _list(value, "actualPaths")
    if not paths:
        raise ConfigError("actualPaths is empty: the file holds no robot")
    for r, path in enumerate(paths):
        if not isinstance(path, str):
            raise ConfigError(f"actualPaths[{r}] is {show(path)}, not a string of actions")
    if not paths[0]:
        raise ConfigError("actualPaths[0] is empty: the episode has no timestep to show")
    steps = paths[0].count(",") + 1
    commas = "," * (steps - 1)
    allowed = set(letters)
    for r, path in enumerate(paths):
        # One letter, then ",letter" per further timestep: letters at even offsets.
        if len(path) != 2 * steps - 1 or path[1::2] != commas or not set(path[::2]) <= allowed:
            raise ConfigError(f"actualPaths[{r}]: {_path_problem(path, steps, letters)}")
    text = "".join(path[::2] for path in paths).encode("ascii")
    return np.frombuffer(text, dtype=np.uint8).reshape(len(paths), steps).T.copy()


def _path_problem(path: str, steps: int, letters: str) -> str:
    """What is wrong with one robot's actions (the first bad one, or its length)."""
    actions = path.split(",")
    for t, action in enumerate(actions):
        if len(action) != 1 or action not in letters:
            return (
                f"action {show(action)} at timestep {t} is not one of {', '.join(letters)} "
                "(one letter per timestep, comma-separated)"
            )
    return (
        f"{len(actions)} actions, but actualPaths[0] has {steps}; every robot needs one per "
        "timestep"
    )


def _starts(value: Any, robots: int, model: str) -> tuple[np.ndarray, np.ndarray]:
    """``start``: ``(row, column)`` and heading of every robot."""
    entries = _list(value, "start")
    if len(entries) != robots:
        raise ConfigError(
            f"start has {_count(len(entries), 'entry', 'entries')} but actualPaths has "
            f"{robots} robots; each "
            "robot needs one [row, column, heading]"
        )
    allowed = HEADINGS + ((NO_HEADING,) if model == "MAPF" else ())
    cells = np.zeros((robots, 2), dtype=np.int64)
    heading = np.full(robots, -1, dtype=np.int64)
    for r, entry in enumerate(entries):
        key = f"start[{r}]"
        # LoRR's lifelong writes a south heading as "S", "W" (a switch that falls
        # through, v2.1.2 Simulator::starts_to_json): read as south, nothing else is.
        if isinstance(entry, list) and len(entry) == 4 and entry[2:] == ["S", "W"]:
            entry = entry[:3]
        if not isinstance(entry, list) or len(entry) != 3:
            raise ConfigError(f"{key} is {show(entry)}; a start is [row, column, heading]")
        cells[r] = integer(entry[0], f"{key} row", 0), integer(entry[1], f"{key} column", 0)
        if entry[2] not in allowed:
            raise ConfigError(
                f"{key} heading {show(entry[2])} is not one of {', '.join(allowed)}"
                + (" (MAPF_T robots turn: each needs a heading)" if entry[2] == NO_HEADING else "")
            )
        heading[r] = HEADINGS.index(entry[2]) if entry[2] in HEADINGS else -1
    return cells, heading


def _tasks(value: Any, layout: Layout) -> dict[int, tuple[int, np.ndarray]]:
    """``tasks``: id -> (release, errands ``[L, 2]`` (row, column)) on free cells."""
    tasks: dict[int, tuple[int, np.ndarray]] = {}
    for i, entry in enumerate(_list(value, "tasks")):
        key = f"tasks[{i}]"
        if not isinstance(entry, list) or len(entry) != 3 or not isinstance(entry[2], list):
            raise ConfigError(
                f"{key} is {show(entry)}; a task is [id, release timestep, [row, column, ...]]"
            )
        tid = integer(entry[0], f"{key} id", 0)
        if tid in tasks:
            raise ConfigError(f"{key}: task id {tid} is used twice")
        release = integer(entry[1], f"{key} release timestep", 0)
        coords = entry[2]
        if not coords or len(coords) % 2:
            raise ConfigError(
                f"{key} (task {tid}) has {len(coords)} coordinates; its errands are "
                "(row, column) pairs, at least one"
            )
        errands = np.array(
            [
                (integer(coords[j], f"{key} errand {j // 2 + 1} row", 0, layout.height),
                 integer(coords[j + 1], f"{key} errand {j // 2 + 1} column", 0, layout.width))
                for j in range(0, len(coords), 2)
            ],
            dtype=np.int64,
        )  # fmt: skip
        blocked = layout.obstacles[errands[:, 0], errands[:, 1]]
        if blocked.any():
            row, col = (int(v) for v in errands[int(np.argmax(blocked))])
            raise ConfigError(
                f"{key} (task {tid}): errand (row {row}, column {col}) is an obstacle"
            )
        tasks[tid] = (release, errands)
    return tasks


def _events(
    value: Any, robots: int, steps: int, tasks: dict[int, tuple[int, np.ndarray]]
) -> np.ndarray:
    """``events`` as ``int64 [E, 4]``; a task's errands in order, in time, by one robot."""
    rows = []
    reached: dict[int, tuple[int, int, int]] = {}  # task -> (errand, timestep, robot)
    for i, entry in enumerate(_list(value, "events")):
        key = f"events[{i}]"
        if not isinstance(entry, list) or len(entry) != 4:
            raise ConfigError(
                f"{key} is {show(entry)}; an event is [timestep, robot, task, errand]"
            )
        t = integer(entry[0], f"{key} timestep", 0, steps + 1)
        robot = integer(entry[1], f"{key} robot", 0, robots)
        task = integer(entry[2], f"{key} task", 0)
        if task not in tasks:
            raise ConfigError(f"{key} names task {task}, which tasks does not hold")
        seq = integer(entry[3], f"{key} errand", 1, len(tasks[task][1]) + 1)
        last, when, by = reached.get(task, (0, 0, robot))
        if seq != last + 1:
            done = "was already reached" if seq <= last else f"comes before its errand {last + 1}"
            raise ConfigError(f"{key}: errand {seq} of task {task} {done}")
        if t < when:
            raise ConfigError(
                f"{key}: errand {seq} of task {task} at timestep {t} is before its errand "
                f"{last} at timestep {when}"
            )
        if robot != by:
            raise ConfigError(f"{key}: robot {robot} reaches task {task}, which robot {by} serves")
        reached[task] = (seq, t, robot)
        rows.append((t, robot, task, seq))
    return np.array(rows, dtype=np.int64).reshape(-1, 4)


def _assignments(
    value: Any, robots: int, steps: int, tasks: dict[int, tuple[int, np.ndarray]]
) -> np.ndarray:
    """``actualSchedule`` as ``int64 [A, 3]`` ``(robot, timestep, task id)``."""
    texts = _list(value, "actualSchedule")
    if len(texts) != robots:
        raise ConfigError(
            f"actualSchedule has {_count(len(texts), 'entry', 'entries')} but actualPaths has "
            f"{robots} robots"
        )
    rows = []
    for robot, text in enumerate(texts):
        key = f"actualSchedule[{robot}]"
        if not isinstance(text, str):
            raise ConfigError(f"{key} is {show(text)}, not a string of 'timestep:task'")
        previous = 0
        for entry in text.split(",") if text else []:
            when, colon, task = entry.partition(":")
            if not colon or not _NUMBER.fullmatch(when) or not _NUMBER.fullmatch(task):
                raise ConfigError(
                    f"{key} entry {show(entry)} is not 'timestep:task' (two integers)"
                )
            t, tid = int(when), int(task)
            if not 0 <= t <= steps:
                raise ConfigError(f"{key} entry {show(entry)}: timestep {t} is outside 0..{steps}")
            if t < previous:
                raise ConfigError(
                    f"{key} entry {show(entry)}: timestep {t} is before the previous entry's "
                    f"{previous}"
                )
            if tid != -1 and tid not in tasks:
                raise ConfigError(
                    f"{key} entry {show(entry)} names task {tid}, which tasks does not hold"
                )
            if tid != -1 and t < tasks[tid][0]:
                raise ConfigError(
                    f"{key} entry {show(entry)}: task {tid} is assigned before its release "
                    f"at timestep {tasks[tid][0]}"
                )
            previous = t
            rows.append((robot, t, tid))
    return np.array(rows, dtype=np.int64).reshape(-1, 3)
