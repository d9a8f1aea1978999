"""The viewer's data: move codes, congestion, throughput, the page, and saved schedules
(LoRR output files) read back into the same episode."""

from __future__ import annotations

import base64
import json
import re
import zlib
from pathlib import Path

import numpy as np
import pytest

from rtaw_marl.errors import ConfigError
from rtaw_marl.integrations.lorr.output import read_schedule, write_episode
from rtaw_marl.sim.layout import Layout
from rtaw_marl.sim.mapf.schedule import Schedule
from rtaw_marl.viz.episode_data import (
    MOVES,
    episode_arrays,
    layout_cells,
    move_codes,
    open_tasks,
    turn_codes,
)
from rtaw_marl.viz.view import ViewEpisode, fill, page, write_view
from tests.viz.episodes import played

pytestmark = pytest.mark.unit


@pytest.fixture
def layout() -> Layout:
    grid = np.zeros((4, 6), dtype=bool)
    grid[3, 5] = True
    pickup = np.zeros_like(grid)
    pickup[0, 0] = True
    return Layout(grid, name="tiny", pickup=pickup)


@pytest.fixture
def schedule() -> Schedule:
    """Robot 0 goes right along row 0 with one wait; robot 1 waits twice then goes down.

    Task 0 (robot 0): assigned 0, pickup 2, delivered 5. Task 1 (robot 1): assigned 1,
    pickup 1, delivered 4.
    """
    r0 = [(0, 0), (1, 0), (2, 0), (2, 0), (3, 0), (4, 0)]
    r1 = [(5, 0), (5, 0), (5, 0), (5, 1), (5, 2), (5, 2)]
    return Schedule(
        positions=np.array([r0, r1], dtype=np.int64).transpose(1, 0, 2),
        tasks=np.array([[2, 0, 4, 0], [5, 0, 5, 2]], dtype=np.int64),
        task_robot=np.array([0, 1]),
        task_arrival=np.array([0, 0]),
        task_assigned=np.array([0, 1]),
        task_pickup=np.array([2, 1]),
        task_delivered=np.array([5, 4]),
    )


def test_move_codes_rebuild_positions(schedule: Schedule) -> None:
    codes = move_codes(schedule.positions)
    assert codes[:, 0].tolist() == [1, 1, 0, 1, 1]
    assert codes[:, 1].tolist() == [0, 0, 3, 3, 0]
    steps = np.array(MOVES)[codes]  # [T, M, 2]
    rebuilt = schedule.positions[0] + np.concatenate([np.zeros((1, 2, 2)), steps.cumsum(0)])
    assert np.array_equal(rebuilt, schedule.positions)


def test_a_jump_is_refused(schedule: Schedule) -> None:
    jumped = schedule.positions.copy()
    jumped[3, 1] = (2, 3)
    with pytest.raises(ConfigError, match="robot 1 moves more than one cell at timestep 2"):
        move_codes(jumped)


def test_congestion_counts_waits_of_robots_with_tasks(layout: Layout, schedule: Schedule) -> None:
    arrays = episode_arrays(layout, schedule, bins=5)
    assert arrays.bin_size == 1
    heat = arrays.congestion.reshape(5, 4, 6)
    # Robot 0 waits at (2, 0) from t = 2 to 3 (busy). Robot 1 waits at (5, 0) from
    # t = 0 (idle: not counted) and t = 1 (assigned at 1: counted), and at (5, 2) from
    # t = 4 (delivered at 4: idle, not counted).
    assert heat.sum() == 2
    assert heat[2, 0, 2] == 1
    assert heat[1, 0, 5] == 1
    assert arrays.delivered.tolist() == [0, 0, 0, 0, 1, 1]
    assert arrays.tasks[:, 4].tolist() == [0, 1]  # numbered by assignment time
    assert layout_cells(layout)[0, 0] == 2
    assert layout_cells(layout)[3, 5] == 1


def test_schedule_off_the_grid_is_refused(layout: Layout, schedule: Schedule) -> None:
    wide = Layout(np.zeros((4, 5), dtype=bool), name="narrow")
    with pytest.raises(ConfigError, match="leaves the 5x4 grid of 'narrow'"):
        episode_arrays(wide, schedule)
    assert episode_arrays(layout, schedule).moves.shape == (5, 2)


def _data(text: str) -> dict:
    match = re.search(r'<script id="rtaw-data" type="application/json">(.*?)</script>', text, re.S)
    assert match is not None
    return json.loads(match.group(1))


def _array(entry: dict) -> np.ndarray:
    raw = zlib.decompress(base64.b64decode(entry["data"]))
    return np.frombuffer(raw, dtype=entry["dtype"]).reshape(entry["shape"])


def test_page_is_self_contained_and_holds_the_episode(layout: Layout, schedule: Schedule) -> None:
    text = page(layout, [ViewEpisode("a</script>", schedule, {"TTD": 3.0})], "t<i>")
    assert "<title>t&lt;i&gt;</title>" in text
    assert not re.search(r"(src|href)=\"?(https?:)?//", text)  # nothing fetched
    data = _data(text)
    (ep,) = data["episodes"]
    assert ep["name"] == "a</script>"
    assert (data["width"], data["height"]) == (6, 4)
    assert np.array_equal(_array(ep["moves"]), move_codes(schedule.positions).T)
    assert np.array_equal(_array(ep["start"]), schedule.positions[0])
    assert _array(data["cells"]).reshape(4, 6)[3, 5] == 1


def test_placeholders_in_user_text_stay_text(layout: Layout, schedule: Schedule) -> None:
    """A title or an episode name that reads like the page's placeholders is not filled
    in: the template is filled in one pass, and user text is never searched again."""
    title = "__SCRIPT__ __STYLE__ __DATA__ __TITLE__"
    text = page(layout, [ViewEpisode("__DATA__", schedule)], title)
    assert f"<title>{title}</title>" in text
    assert text.count("window.rtawView =") == 1
    assert text.count("<style>") == 1
    data = _data(text)
    assert data["title"] == title
    assert data["episodes"][0]["name"] == "__DATA__"
    rest = text.replace(title, "").replace('"name":"__DATA__"', "")
    assert not re.search(r"__(TITLE|STYLE|SCRIPT|DATA)__", rest)  # every placeholder filled


def test_fill_is_one_pass() -> None:
    parts = {"TITLE": "__DATA__", "STYLE": "s", "SCRIPT": "__TITLE__", "DATA": "d"}
    assert fill("__TITLE__|__STYLE__|__SCRIPT__|__DATA__", parts) == "__DATA__|s|__TITLE__|d"


def test_page_refuses_three_episodes_and_mixed_fleets(layout: Layout, schedule: Schedule) -> None:
    one = ViewEpisode("a", schedule)
    with pytest.raises(ConfigError, match="1 or 2 episodes, got 3"):
        page(layout, [one] * 3, "x")
    small = Schedule(
        schedule.positions[:, :1], schedule.tasks[:1], schedule.task_robot[:1],
        schedule.task_arrival[:1], schedule.task_assigned[:1], schedule.task_pickup[:1],
        schedule.task_delivered[:1],
    )  # fmt: skip
    with pytest.raises(ConfigError, match="same number of robots"):
        page(layout, [one, ViewEpisode("b", small)], "x")


def test_saved_schedule_round_trip(layout: Layout, schedule: Schedule, tmp_path: Path) -> None:
    """rtaw-render's LoRR output reads back to the same positions and task times."""
    path = write_episode(schedule, tmp_path / "episode.json")
    back = read_schedule(path, layout)
    assert np.array_equal(back.positions, schedule.positions)
    order = np.argsort(schedule.task_assigned, kind="stable")
    assert np.array_equal(back.tasks, schedule.tasks[order])
    for key in ("task_robot", "task_assigned", "task_pickup", "task_delivered"):
        assert np.array_equal(getattr(back, key), getattr(schedule, key)[order]), key
    out = write_view(tmp_path / "v.html", layout, [ViewEpisode("saved", back)], "saved")
    assert out.stat().st_size > 0


def test_saved_schedule_of_an_unfinished_task(
    layout: Layout, schedule: Schedule, tmp_path: Path
) -> None:
    """Cut at t = 3: task 0 is picked up (t = 2), not delivered: delivered = T + 1."""
    path = write_episode(schedule, tmp_path / "cut.json", horizon=3)
    back = read_schedule(path, layout)
    assert back.horizon == 3
    assert back.task_pickup.tolist() == [2, 1]
    assert back.task_delivered.tolist() == [4, 4]  # task 0 not delivered by 3; task 1 at 4 > 3


def test_bad_saved_schedule(layout: Layout, tmp_path: Path) -> None:
    bad = tmp_path / "bad.json"
    bad.write_text("{", encoding="utf-8")
    with pytest.raises(ConfigError, match="not a LoRR output file"):
        read_schedule(bad, layout)


def test_open_tasks_are_the_last_assignments_the_schedule_leaves_out(
    layout: Layout, schedule: Schedule
) -> None:
    """Robot 0 gets task 2 at t = 5 standing on its origin (pickup 5); robot 1 gets task
    3 at t = 4 and never reaches its origin (pickup T + 1 = 6); task 4 was never given."""
    tasks = np.array(
        [[2, 0, 4, 0], [5, 0, 5, 2], [4, 0, 0, 0], [0, 3, 1, 1], [3, 3, 3, 3]], dtype=np.int64
    )
    robot = np.array([0, 1, 0, 1, -1])
    arrival = np.array([0.0, 0.0, 2.0, 3.0, 4.0])
    assigned = np.array([0.0, 1.0, 5.0, 4.0, np.nan])
    rows = open_tasks(schedule, tasks, robot, arrival, assigned)
    assert rows.tolist() == [[4, 0, 0, 0, 0, 2, 5, 5, 6, 2], [0, 3, 1, 1, 1, 3, 4, 6, 6, 3]]
    arrays = episode_arrays(layout, schedule, unfinished=rows)
    assert arrays.tasks[:, 6].tolist() == [0, 1, 4, 5]  # numbered by assignment time
    assert arrays.delivered.sum() == 2  # the open tasks are not delivered
    # Robot 1 holds task 3 from t = 4: its wait at (5, 2) from t = 4 is congestion now.
    assert arrays.congestion.reshape(-1, 4, 6)[4, 2, 5] == 1


def test_a_horizon_episode_shows_every_assigned_task(tmp_path: Path) -> None:
    """PIBT, a LoRR problem, 40 timesteps: the schedule's tasks and the open ones are
    every task the simulator assigned; each open pickup is at the task's origin."""
    from rtaw_marl.evaluation.evaluate import run_episode
    from rtaw_marl.policies import make_baseline
    from rtaw_marl.scenarios.lorr import lorr_scenario
    from rtaw_marl.sim.builder import build_sim
    from tests.cli.test_eval_cli import _tiny_lorr_problem

    sim = build_sim(lorr_scenario(_tiny_lorr_problem(tmp_path), horizon=40).spec())
    run_episode(sim, make_baseline("mpdm"), 0)
    schedule = sim.schedule()
    rows = open_tasks(schedule, sim.tasks, sim.task_robot, sim.task_arrival, sim.task_assigned)
    assert len(rows) >= 1
    assert len(schedule.tasks) + len(rows) == int((sim.task_robot >= 0).sum())
    # Their ids are the simulator's stream indices, each assigned task once.
    assert schedule.task_ids is not None
    ids = np.concatenate([schedule.task_ids, rows[:, 9]])
    assert np.array_equal(np.sort(ids), np.flatnonzero(sim.task_robot >= 0))
    for ox, oy, _, _, robot, _, at, pickup, delivered, _ in rows.tolist():
        assert delivered == schedule.horizon + 1
        assert at <= pickup
        if pickup <= schedule.horizon:
            assert schedule.positions[pickup, robot].tolist() == [ox, oy]


def test_stream_task_ids_agree_between_two_episodes_of_one_seed() -> None:
    """Two policies on one seed: a task id names the same task (the same cells, the
    stream's) in both pages' rows, though the policies assign tasks in different orders
    (the rank of assignment, the old id, names different tasks)."""
    sim, schedules, _ = played(("mpdm", "lookahead"), 3)
    rows = {}
    for name, schedule in schedules.items():
        tasks = episode_arrays(sim.layout, schedule).tasks
        rows[name] = {int(r[9]): r for r in tasks}
        assert len(rows[name]) == len(tasks)  # ids unique
        for i, r in rows[name].items():
            assert r[:4].tolist() == sim.tasks[i].tolist()  # the stream's task i
    a, b = rows.values()
    common = sorted(set(a) & set(b))
    assert len(common) >= 20
    for i in common:
        assert a[i][:4].tolist() == b[i][:4].tolist()
    rank = [{int(r[9]): k for k, r in enumerate(episode_arrays(sim.layout, s).tasks)}
            for s in schedules.values()]  # fmt: skip
    assert any(rank[0][i] != rank[1][i] for i in common)


def test_a_saved_file_keeps_the_stream_ids(tmp_path: Path) -> None:
    """rtaw-render's LoRR output writes stream ids as its task ids; the reader keeps
    them: the page of the file and the page of the played episode agree."""
    sim, schedules, _ = played(("mpdm",), 3)
    schedule = schedules["mpdm"]
    assert schedule.task_ids is not None
    back = read_schedule(write_episode(schedule, tmp_path / "e.json"), sim.layout)
    shown = episode_arrays(sim.layout, schedule).tasks
    saved = episode_arrays(sim.layout, back).tasks
    assert np.array_equal(np.sort(saved[:, 9]), np.sort(shown[:, 9]))
    by_id = {int(r[9]): r.tolist() for r in shown}
    for r in saved:
        assert r.tolist() == by_id[int(r[9])]


def test_headings_read_from_a_mapf_t_file() -> None:
    """LoRR's turning model: robot 0 faces east and goes forward; robot 1 faces south,
    turns clockwise (west) at t = 0, then goes forward. The page gets the start headings
    and the quarter turns, robot by robot; a MAPF file gets neither."""
    from rtaw_marl.viz.schedule_file import read_schedule_data
    from tests.viz.saved_files import tiny_layout, valid

    layout = tiny_layout()
    saved = read_schedule_data(valid("MAPF_T"), layout).schedule
    ep = _data(page(layout, [ViewEpisode("turns", saved)], "t"))["episodes"][0]
    assert _array(ep["headings"]).tolist() == [0, 1]
    assert _array(ep["turns"]).tolist() == [[0, 0, 0], [1, 0, 0]]
    assert _array(ep["tasks"])[:, 9].tolist() == [0, 1]  # the file's task ids
    plain = read_schedule_data(valid("MAPF"), layout).schedule
    ep = _data(page(layout, [ViewEpisode("plain", plain)], "t"))["episodes"][0]
    assert "headings" not in ep
    assert "turns" not in ep


def test_a_half_turn_is_refused() -> None:
    headings = np.array([[0, 1], [1, 3], [1, 0]])
    assert turn_codes(headings[:2, :1]).tolist() == [[1]]
    with pytest.raises(ConfigError, match="robot 1 turns half round at timestep 0"):
        turn_codes(headings)
    with pytest.raises(ConfigError, match="robot 0 has heading 4 at timestep 1"):
        turn_codes(np.array([[0], [4]]))
