"""The one reader of saved episodes (``rtaw-view schedule=``): every field checked in
full, each problem one line naming the file, the entry and what is wrong."""

from __future__ import annotations

import json
import re
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from rtaw_marl.errors import ConfigError
from rtaw_marl.integrations.lorr.output import write_episode
from rtaw_marl.sim.mapf.schedule import Schedule
from rtaw_marl.viz.schedule_file import ScheduleFileError, read_schedule_file
from tests.viz.saved_files import tiny_layout, valid, write

pytestmark = pytest.mark.unit

Edit = Callable[[dict[str, Any]], Any]


def _set(key: str, value: Any) -> Edit:
    def edit(d: dict[str, Any]) -> None:
        d[key] = value

    return edit


def _at(key: str, index: int, value: Any) -> Edit:
    def edit(d: dict[str, Any]) -> None:
        d[key][index] = value

    return edit


def _drop(key: str) -> Edit:
    def edit(d: dict[str, Any]) -> None:
        del d[key]

    return edit


#: (what the tester saw or its kin, edit of the valid file, what the message says)
CASES: list[tuple[str, Edit, str]] = [
    # The cases found by the tester.
    (
        "heading Q",
        _at("start", 1, [2, 5, "Q"]),
        "start[1] heading 'Q' is not one of E, S, W, N, N/A",
    ),
    (
        "event at -1",
        _at("events", 0, [-1, 0, 0, 1]),
        "events[0] timestep is -1; it must be in 0..3",
    ),
    (
        "delivery before pickup",
        _set("events", [[2, 1, 1, 1], [1, 1, 1, 2]]),
        "events[1]: errand 2 of task 1 at timestep 1 is before its errand 1 at timestep 2",
    ),
    (
        "task off the map",
        _at("tasks", 0, [0, 0, [0, 2, 9, 3]]),
        "tasks[0] errand 2 row is 9; it must be in 0..2",
    ),
    (
        "heading Q, turning",
        lambda d: d.update(
            actionModel="MAPF_T", actualPaths=["F,F,W", "R,F,F"], start=[[0, 0, "E"], [2, 5, "Q"]]
        ),
        "start[1] heading 'Q' is not one of E, S, W, N",
    ),
    ("start not numbers", _at("start", 0, ["a", "b", "N"]), "start[0] row is 'a', not an integer"),
    ("NaN start", _at("start", 0, [float("nan"), 0, "N/A"]), "start[0] row is nan, not an integer"),
    (
        "one start for two",
        _set("start", [[0, 0, "N/A"]]),
        "start has 1 entry but actualPaths has 2 robots",
    ),
    (
        "three starts for two",
        _set("start", [[0, 0, "N/A"], [2, 5, "N/A"], [2, 0, "N/A"]]),
        "start has 3 entries but actualPaths has 2 robots",
    ),
    ("no paths", _set("actualPaths", []), "actualPaths is empty: the file holds no robot"),
    (
        "event of 3 fields",
        _at("events", 0, [2, 0, 0]),
        "events[0] is a list of 3 items; an event is [timestep, robot, task, errand]",
    ),
    ("event robot a", _at("events", 0, [2, "a", 0, 1]), "events[0] robot is 'a', not an integer"),
    (
        "event robot 999",
        _at("events", 0, [2, 999, 0, 1]),
        "events[0] robot is 999; it must be in 0..1",
    ),
    (
        "task of 3 coordinates",
        _at("tasks", 0, [0, 0, [0, 2, 0]]),
        "tasks[0] (task 0) has 3 coordinates; its errands are (row, column) pairs",
    ),
    (
        "schedule 0:abc",
        _at("actualSchedule", 0, "0:abc"),
        "actualSchedule[0] entry '0:abc' is not 'timestep:task' (two integers)",
    ),
    # The same kinds, elsewhere in the file.
    ("not an object", lambda d: [d], "holds a list of 1 item, not a JSON object"),
    ("no events key", _drop("events"), "has no 'events' key"),
    ("no actualSchedule key", _drop("actualSchedule"), "has no 'actualSchedule' key"),
    (
        "action model",
        _set("actionModel", "MAPF_X"),
        "actionModel is 'MAPF_X', not one of MAPF, MAPF_T",
    ),
    (
        "path not a string",
        _at("actualPaths", 1, ["W", "L", "L"]),
        "actualPaths[1] is a list of 3 items, not a string of actions",
    ),
    ("empty path", _set("actualPaths", ["", ""]), "actualPaths[0] is empty"),
    (
        "short path",
        _at("actualPaths", 1, "W,L"),
        "actualPaths[1]: 2 actions, but actualPaths[0] has 3",
    ),
    (
        "unknown action",
        _at("actualPaths", 1, "W,X,L"),
        "actualPaths[1]: action 'X' at timestep 1 is not one of U, D, R, L, W, T",
    ),
    ("two letters", _at("actualPaths", 1, "W,LL"), "actualPaths[1]: action 'LL' at timestep 1"),
    ("turning action in MAPF", _at("actualPaths", 0, "F,F,W"), "action 'F' at timestep 0"),
    (
        "N/A heading when turning",
        lambda d: d.update(actionModel="MAPF_T", actualPaths=["F,F,W", "R,F,F"]),
        "start[0] heading 'N/A' is not one of E, S, W, N (MAPF_T robots turn",
    ),
    ("start of 2 fields", _at("start", 0, [0, 0]), "start[0] is a list of 2 items; a start is"),
    ("bool as a number", _at("start", 0, [True, 0, "N/A"]), "start[0] row is true, not an integer"),
    (
        "float as a number",
        _at("events", 0, [2.0, 0, 0, 1]),
        "events[0] timestep is 2.0, not an integer",
    ),
    ("teamSize", _set("teamSize", 3), "teamSize is 3 but actualPaths has 2 robots"),
    ("numTaskFinished", _set("numTaskFinished", 2), "numTaskFinished is 2 but its events finish 1"),
    ("task not a list", _at("tasks", 0, "t0"), "tasks[0] is 't0'; a task is [id, release"),
    ("task id twice", _at("tasks", 2, [0, 1, [0, 5, 2, 0]]), "tasks[2]: task id 0 is used twice"),
    (
        "negative release",
        _at("tasks", 2, [2, -4, [0, 5, 2, 0]]),
        "tasks[2] release timestep is -4; it must be at least 0",
    ),
    (
        "errand on an obstacle",
        _at("tasks", 2, [2, 1, [1, 1, 2, 0]]),
        "tasks[2] (task 2): errand (row 1, column 1) is an obstacle",
    ),
    ("no errand", _at("tasks", 2, [2, 1, []]), "tasks[2] (task 2) has 0 coordinates"),
    (
        "event of an unknown task",
        _at("events", 0, [2, 0, 7, 1]),
        "events[0] names task 7, which tasks",
    ),
    ("errand 3 of 2", _at("events", 2, [3, 1, 1, 3]), "events[2] errand is 3; it must be in 1..2"),
    (
        "errand twice",
        _at("events", 2, [3, 1, 1, 1]),
        "events[2]: errand 1 of task 1 was already reached",
    ),
    (
        "errand skipped",
        _set("events", [[3, 1, 1, 2]]),
        "events[0]: errand 2 of task 1 comes before",
    ),
    (
        "another robot",
        _set("events", [[2, 1, 1, 1], [3, 0, 1, 2]]),
        "events[1]: robot 0 reaches task 1, which robot 1 serves",
    ),
    (
        "event after the end",
        _at("events", 2, [4, 1, 1, 2]),
        "events[2] timestep is 4; it must be in 0..3",
    ),
    (
        "schedule length",
        _set("actualSchedule", ["0:0"]),
        "actualSchedule has 1 entry but actualPaths has 2 robots",
    ),
    ("schedule not a string", _at("actualSchedule", 1, 5), "actualSchedule[1] is 5, not a string"),
    ("schedule no colon", _at("actualSchedule", 0, "0"), "actualSchedule[0] entry '0' is not"),
    (
        "schedule unknown task",
        _at("actualSchedule", 0, "0:9"),
        "actualSchedule[0] entry '0:9' names task 9, which tasks does not hold",
    ),
    (
        "schedule out of order",
        _at("actualSchedule", 1, "2:2,1:1"),
        "actualSchedule[1] entry '1:1': timestep 1 is before the previous entry's 2",
    ),
    ("schedule after the end", _at("actualSchedule", 1, "9:1"), "timestep 9 is outside 0..3"),
    (
        "task taken away",
        _at("actualSchedule", 1, "1:1,2:-1"),
        "events[2]: robot 1 reaches task 1 at timestep 3, but actualSchedule[1] took its task "
        "away at timestep 2",
    ),
    (
        "another task meanwhile",
        _at("actualSchedule", 1, "1:1,2:2"),
        "actualSchedule[1] gave it task 2 at timestep 2",
    ),
    ("schedule at -1", _at("actualSchedule", 1, "-1:1"), "entry '-1:1': timestep -1 is outside"),
    (
        "assigned before release",
        _at("actualSchedule", 0, "0:0,0:2"),
        "actualSchedule[0] entry '0:2': task 2 is assigned before its release at timestep 1",
    ),
    (
        "reached unassigned",
        _set("actualSchedule", ["0:0", ""]),
        "events[1]: robot 1 reaches task 1 at timestep 2, but actualSchedule does not assign",
    ),
    (
        "assigned after reached",
        _set("actualSchedule", ["0:0", "3:1"]),
        "events[1]: robot 1 reaches",
    ),
    # What the episode does, replayed.
    (
        "onto an obstacle",
        _at("actualPaths", 0, "R,U,W"),
        "robot 0 is at (row 1, column 1), an obstacle, at timestep 2",
    ),
    (
        "off the map",
        _at("actualPaths", 0, "D,W,W"),
        "robot 0 is at (row -1, column 0), outside the 6x3 map, at timestep 1",
    ),
    (
        "event away from its errand",
        _at("events", 0, [1, 0, 0, 1]),
        "events[0]: robot 0 is at (row 0, column 1) at timestep 1, not at errand 1 of task 0",
    ),
    (
        "two in a cell",
        lambda d: d.update(
            start=[[0, 0, "N/A"], [0, 1, "N/A"]],
            actualPaths=["R,W,W", "W,W,W"],
            events=[],
            actualSchedule=["", ""],
            numTaskFinished=0,
        ),
        "robots 0 and 1 share a cell at timestep 1",
    ),
    (
        "swap",
        lambda d: d.update(
            start=[[0, 0, "N/A"], [0, 1, "N/A"]],
            actualPaths=["R,W,W", "L,W,W"],
            events=[],
            actualSchedule=["", ""],
            numTaskFinished=0,
        ),
        "robots 0 and 1 swap cells at timestep 1",
    ),
]


@pytest.mark.parametrize(("edit", "message"), [c[1:] for c in CASES], ids=[c[0] for c in CASES])
def test_a_bad_field_is_one_line_naming_it(edit: Edit, message: str, tmp_path: Path) -> None:
    data = valid()
    data = edit(data) or data
    path = write(tmp_path / "s.json", data)
    with pytest.raises(ScheduleFileError) as info:
        read_schedule_file(path, tiny_layout())
    text = str(info.value)
    assert text.startswith(f"schedule {path}: ")
    assert message in text
    assert "\n" not in text
    assert not re.search(r"np\.\w+\(", text)  # no numpy reprs: plain numbers


def test_a_deep_nesting_is_one_line(tmp_path: Path) -> None:
    """200,000 levels: the JSON parser's RecursionError becomes the file's error."""
    path = tmp_path / "deep.json"
    path.write_text("[" * 200_000 + "]" * 200_000, encoding="utf-8")
    with pytest.raises(ScheduleFileError, match=r"deep.json: is nested too deeply"):
        read_schedule_file(path, tiny_layout())


@pytest.mark.parametrize(
    ("raw", "message"),
    [
        (b"{", "is not a LoRR output file (not JSON: Expecting property name"),
        (b"\xff\xfe{", "is not a LoRR output file (not JSON"),
        (b"", "is not a LoRR output file (not JSON: Expecting value"),
    ],
)
def test_not_json_is_one_line(raw: bytes, message: str, tmp_path: Path) -> None:
    path = tmp_path / "s.json"
    path.write_bytes(raw)
    with pytest.raises(ScheduleFileError, match=re.escape(message)):
        read_schedule_file(path, tiny_layout())


def test_an_unreadable_path_is_one_line(tmp_path: Path) -> None:
    with pytest.raises(ScheduleFileError, match=r"cannot be read \("):
        read_schedule_file(tmp_path, tiny_layout())


@pytest.mark.parametrize("model", ["MAPF", "MAPF_T"])
def test_a_valid_file_replays(model: str, tmp_path: Path) -> None:
    """Both action models, LoRR's ``[row, column, "S", "W"]`` start read as south: the
    same cells, tasks 0 and 1 (task 2 was never assigned), task 1 finished."""
    saved = read_schedule_file(write(tmp_path / "s.json", valid(model)), tiny_layout())
    schedule = saved.schedule
    assert saved.tasks_finished == 1
    assert schedule.positions[:, 1].tolist() == [[5, 2], [5, 2], [4, 2], [3, 2]]  # (x, y)
    assert schedule.tasks.tolist() == [[2, 0, 3, 0], [4, 2, 3, 2]]
    assert schedule.task_assigned.tolist() == [0, 1]
    assert schedule.task_pickup.tolist() == [2, 2]
    assert schedule.task_delivered.tolist() == [4, 3]  # task 0 not delivered: T + 1


def test_lorr_unassignments_are_read(tmp_path: Path) -> None:
    """LoRR writes ``t:-1`` when a robot's task is taken away; a reassigned unopened task
    belongs to its latest robot."""
    data = valid()
    data["actualSchedule"] = ["0:0,2:2,3:-1", "1:1,3:2"]
    schedule = read_schedule_file(write(tmp_path / "s.json", data), tiny_layout()).schedule
    assert schedule.task_robot.tolist() == [0, 1, 1]
    assert schedule.task_assigned.tolist() == [0, 1, 3]


def test_the_budget_is_asked_before_the_replay(tmp_path: Path) -> None:
    """The caller's check sees (robots, timesteps) and may refuse before any array."""
    seen = []

    def budget(robots: int, timesteps: int) -> None:
        seen.append((robots, timesteps))
        raise ConfigError("too big")

    with pytest.raises(ScheduleFileError, match=r"s.json: too big"):
        read_schedule_file(write(tmp_path / "s.json", valid()), tiny_layout(), budget)
    assert seen == [(2, 3)]


def test_rtaw_render_output_reads_back(tmp_path: Path) -> None:
    """A schedule written in LoRR's format by rtaw-render's writer: the same cells and
    task times come back (a task unfinished at the end: T + 1)."""
    r0 = [(0, 0), (1, 0), (2, 0), (3, 0)]
    r1 = [(5, 2), (4, 2), (3, 2), (3, 2)]
    schedule = Schedule(
        positions=np.array([r0, r1], dtype=np.int64).transpose(1, 0, 2),
        tasks=np.array([[2, 0, 3, 0], [4, 2, 3, 2]], dtype=np.int64),
        task_robot=np.array([0, 1]),
        task_arrival=np.array([0, 0]),
        task_assigned=np.array([0, 1]),
        task_pickup=np.array([2, 1]),
        task_delivered=np.array([5, 2]),
    )
    path = write_episode(schedule, tmp_path / "e.json")
    data = json.loads(path.read_text())
    assert data["actionModel"] == "MAPF"
    back = read_schedule_file(path, tiny_layout()).schedule
    assert np.array_equal(back.positions, schedule.positions)
    assert back.task_pickup.tolist() == [2, 1]
    assert back.task_delivered.tolist() == [4, 2]
