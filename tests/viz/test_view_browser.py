"""The viewer in a real browser: it loads without errors, plays, reacts to a click on a
robot and to a search, and draws every robot where the schedule puts it, in its state's
colour (two policies side by side on one seed, executed by SIPP)."""

from __future__ import annotations

import io
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from PIL import Image

from rtaw_marl.sim.mapf.schedule import Schedule
from rtaw_marl.viz.view import ViewEpisode, write_view
from tests.viz.browser import browser_or_skip, chromium, open_view, severe_logs
from tests.viz.episodes import played

pytestmark = pytest.mark.system

SEED = 3
POLICIES = ("mpdm", "lookahead")
FREE = (242, 242, 242)
STATE_RGB = {0: (0x8C, 0x8C, 0x8C), 1: (0x1F, 0x6F, 0xD1), 2: (0xE8, 0x71, 0x0A)}


@pytest.fixture(scope="module")
def episodes(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, dict[str, Schedule]]:
    sim, schedules, ttds = played(POLICIES, SEED)
    eps = [ViewEpisode(n, schedules[n], {"TTD": ttds[n], "seed": SEED}) for n in POLICIES]
    path = tmp_path_factory.mktemp("view") / "view.html"
    write_view(path, sim.layout, eps, "test")
    return path, schedules


@pytest.fixture(scope="module")
def page(episodes: tuple[Path, dict[str, Schedule]]) -> Any:
    browser_or_skip()
    with chromium() as driver:
        open_view(driver, episodes[0])
        yield driver


def _state(driver: Any) -> dict[str, Any]:
    return driver.execute_script("return window.rtawView.state()")


def _expected_states(schedule: Schedule, t: int) -> np.ndarray:
    """0 idle, 1 on the way to a pickup, 2 carrying, per robot at timestep ``t``."""
    state = np.zeros(schedule.num_robots, dtype=np.int64)
    holding = (schedule.task_assigned <= t) & (t < schedule.task_delivered)
    robots = schedule.task_robot[holding]
    state[robots] = np.where(t < schedule.task_pickup[holding], 1, 2)
    return state


def _busy_robot(schedule: Schedule, t: int) -> int:
    states = _expected_states(schedule, t)
    return int(np.flatnonzero(states > 0)[0])


def test_loads_without_console_errors(page: Any, episodes: Any) -> None:
    state = _state(page)
    _, schedules = episodes
    assert state["robots"] == [12, 12]
    assert state["steps"] == max(s.horizon for s in schedules.values())
    assert page.execute_script("return window.rtawErrors") == []
    assert severe_logs(page) == []
    assert page.find_element("id", "legend").text.split()[:4] == [
        "idle",
        "to",
        "pickup",
        "carrying",
    ]


def test_plays_and_pauses(page: Any) -> None:
    page.execute_script("window.rtawView.seek(0); window.rtawView.setSpeed(50)")
    page.find_element("id", "play").click()
    time.sleep(0.8)
    playing = _state(page)
    page.find_element("id", "play").click()
    paused = _state(page)
    time.sleep(0.3)
    assert playing["playing"]
    assert playing["t"] > 5
    assert not paused["playing"]
    assert _state(page)["time"] == paused["time"]
    assert severe_logs(page) == []


def _click_cell(page: Any, panel: int, x: int, y: int) -> None:
    from selenium.webdriver.common.action_chains import ActionChains

    cx, cy = page.execute_script(f"return window.rtawView.cellToClient({panel}, {x}, {y})")
    body = page.find_element("tag name", "body")
    origin = body.rect
    ActionChains(page).move_to_element_with_offset(
        body, int(cx - origin["width"] / 2), int(cy - origin["height"] / 2)
    ).click().perform()


def test_click_on_a_robot_shows_its_task(page: Any, episodes: Any) -> None:
    _, schedules = episodes
    schedule, t = schedules["mpdm"], 20
    robot = _busy_robot(schedule, t)
    page.execute_script(f"window.rtawView.seek({t})")
    x, y = schedule.positions[t, robot]
    _click_cell(page, 0, int(x), int(y))
    state = _state(page)
    assert state["selected"] == robot
    j = next(
        j
        for j in range(len(schedule.tasks))
        if schedule.task_robot[j] == robot and schedule.task_assigned[j] <= t
        and t < schedule.task_delivered[j]
    )  # fmt: skip
    ox, oy, dx, dy = schedule.tasks[j]
    assert schedule.task_ids is not None
    assert f"robot {robot}" in state["info"]
    # The task by its stream id (the simulator's), not by its rank of assignment.
    assert f"task {schedule.task_ids[j]}: ({ox}, {oy}) -> ({dx}, {dy})" in state["info"]
    # A click on a cell with no robot clears the selection.
    free = np.argwhere(~_occupied(schedule, t))[0]
    _click_cell(page, 0, int(free[1]), int(free[0]))
    assert _state(page)["selected"] == -1


def _occupied(schedule: Schedule, t: int) -> np.ndarray:
    grid = np.zeros((60, 60), dtype=bool)
    for x, y in schedule.positions[t]:
        grid[max(0, y - 1) : y + 2, max(0, x - 1) : x + 2] = True
    return grid


def test_search_finds_and_follows(page: Any, episodes: Any) -> None:
    """``t<id>`` is the task of that stream id in both panels: each panel selects the
    robot that serves it in its own episode, centred there."""
    _, schedules = episodes
    rows = {}
    for name, schedule in schedules.items():
        assert schedule.task_ids is not None
        rows[name] = {int(i): j for j, i in enumerate(schedule.task_ids)}
    first, second = (schedules[n] for n in POLICIES)
    # A task both episodes assigned, to different robots (ids differ from ranks).
    task = next(
        i for i in sorted(rows["mpdm"])
        if i in rows["lookahead"]
        and first.task_robot[rows["mpdm"][i]] != second.task_robot[rows["lookahead"][i]]
    )  # fmt: skip
    box = page.find_element("id", "search")
    box.clear()
    box.send_keys(f"t{task}\n")
    state = _state(page)
    j = rows["mpdm"][task]
    assert state["task"] == task
    assert state["selectedRobots"] == [
        first.task_robot[j],
        second.task_robot[rows["lookahead"][task]],
    ]
    assert state["follow"]
    assert first.task_assigned[j] <= state["t"] < first.task_delivered[j]
    assert f"task {task}: " in state["info"]
    # Followed: each panel's robot is drawn at the centre of its panel.
    rects = page.execute_script(
        "return [...document.querySelectorAll('.panel canvas')]"
        ".map(c => c.getBoundingClientRect().toJSON())"
    )
    for panel, name in enumerate(POLICIES):
        robot = state["selectedRobots"][panel]
        x, y = schedules[name].positions[min(state["t"], schedules[name].horizon), robot]
        cx, cy = page.execute_script(f"return window.rtawView.cellToClient({panel}, {x}, {y})")
        rect = rects[panel]
        assert abs(cx - (rect["left"] + rect["width"] / 2)) < state["scale"]
        assert abs(cy - (rect["top"] + rect["height"] / 2)) < state["scale"]
    box.clear()
    box.send_keys("robot 99\n")
    assert _state(page)["selected"] == -1
    assert "no robot 99 (robots 0-11)" in _state(page)["info"]


@pytest.mark.parametrize(("t", "scale"), [(0, 7), (15, 7), (40, 7), (15, 3), (40, 3)])
def test_robots_drawn_where_the_schedule_puts_them(
    page: Any, episodes: Any, t: int, scale: int
) -> None:
    """Zoomed in (7 pixels a cell: rectangles) and out (3: one image, a pixel a cell)."""
    _, schedules = episodes
    page.execute_script("window.rtawView.pause(); document.getElementById('search').blur()")
    page.find_element("tag name", "body").send_keys("\ue00c")  # Escape: no selection ring
    page.execute_script(f"window.rtawView.setCamera({scale}, 4, 24); window.rtawView.seek({t})")
    shot = np.asarray(Image.open(io.BytesIO(page.get_screenshot_as_png())).convert("RGB"))
    for panel, name in enumerate(POLICIES):
        schedule = schedules[name]
        tt = min(t, schedule.horizon)
        states = _expected_states(schedule, tt)
        for robot, (x, y) in enumerate(schedule.positions[tt]):
            cx, cy = page.execute_script(f"return window.rtawView.cellToClient({panel}, {x}, {y})")
            got = tuple(int(v) for v in shot[round(cy), round(cx)])
            want = STATE_RGB[int(states[robot])]
            assert np.abs(np.subtract(got, want)).max() <= 3, (name, robot, tt, got, want)
        free = np.argwhere(~_occupied(schedule, tt) & ~_obstacles(page))[0]
        cx, cy = page.execute_script(
            f"return window.rtawView.cellToClient({panel}, {free[1]}, {free[0]})"
        )
        assert tuple(int(v) for v in shot[round(cy), round(cx)]) == FREE


def _obstacles(page: Any) -> np.ndarray:
    cells = page.execute_script("return Array.from(window.rtawView.cells())")
    return np.asarray(cells).reshape(60, 60) == 1
