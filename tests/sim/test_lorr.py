"""League of Robot Runners 2024 problems: files, errors, the reveal window and PIBT."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from rtaw_marl.errors import ConfigError, TaskFileError
from rtaw_marl.evaluation.evaluate import run_episode
from rtaw_marl.policies import make_baseline
from rtaw_marl.scenarios import lorr_scenario
from rtaw_marl.sim.builder import build_sim
from rtaw_marl.sim.lorr import LORR_HORIZON, read_agents, read_lorr_tasks, read_problem
from rtaw_marl.sim.mapf import check_schedule

pytestmark = pytest.mark.integration

KIT = Path(__file__).resolve().parents[2].parent / "shared" / "lorr" / "start-kit-v2.1.2"
RANDOM = KIT / "example_problems" / "random.domain" / "random_32_32_20_100.json"


def write_problem(root: Path, tasks: str, agents: str = "# version for LoRR 2024\n2\n0\n7\n",
                  **keys: object) -> Path:  # fmt: skip
    """A 4x2 problem: map '....' / '..@.', locations row * 4 + col."""
    (root / "m.map").write_text("type octile\nheight 2\nwidth 4\nmap\n....\n..@.\n")
    (root / "a.agents").write_text(agents)
    (root / "t.tasks").write_text(tasks)
    data = {"mapFile": "m.map", "agentFile": "a.agents", "taskFile": "t.tasks",
            "teamSize": 2, "numTasksReveal": 1.5, **keys}  # fmt: skip
    path = root / "p.json"
    path.write_text(json.dumps(data))
    return path


def test_locations_are_linearized_row_major(tmp_path: Path) -> None:
    """loc = row * width + col: 7 is (x=3, y=1); tasks keep their errands in order."""
    problem = read_problem(write_problem(tmp_path, "# version for LoRR 2024\n2\n1,7\n4,0\n"))
    layout = problem.layout()
    assert read_agents(problem.agents_path, layout).tolist() == [[0, 0], [3, 1]]
    assert read_lorr_tasks(problem.tasks_path, layout).tolist() == [[1, 0, 3, 1], [0, 1, 0, 0]]
    assert (problem.team_size, problem.window(2), problem.window(10)) == (2, 3, 15)


@pytest.mark.parametrize(
    ("tasks", "keys", "message"),
    [
        ("1\n1,7,2\n", {}, r"t\.tasks:2: a task has 3 errands; only pickup-then-delivery"),
        ("2\n1,7\n", {}, r"header says 2 tasks, found 1"),
        ("1\n1,99\n", {}, r"location 99 is outside the 8-cell map"),
        ("1\n1,6\n", {}, r"delivery of task 0 at \(x=2, y=1\) is on an obstacle"),
        ("1\nfoo\n", {}, r"expected comma-separated locations"),
        ("x\n", {}, r"starts with its count, got 'x'"),
        ("1\n1,7\n", {"numTasksReveal": 1}, r"numTasksReveal must be a number above 1"),
        ("1\n1,7\n", {"taskFile": "nope.tasks"}, r"taskFile 'nope\.tasks' not found"),
    ],
)
def test_bad_files_get_one_line_errors(
    tmp_path: Path, tasks: str, keys: dict, message: str
) -> None:
    path = write_problem(tmp_path, tasks, **keys)

    def read() -> None:
        problem = read_problem(path)
        read_lorr_tasks(problem.tasks_path, problem.layout())

    with pytest.raises(ConfigError, match=message) as info:
        read()
    assert "\n" not in str(info.value)


def test_missing_key_and_not_json(tmp_path: Path) -> None:
    path = tmp_path / "p.json"
    path.write_text('{"mapFile": "m.map"}')
    with pytest.raises(TaskFileError, match="misses 'agentFile'"):
        read_problem(path)
    path.write_text("type octile")
    with pytest.raises(TaskFileError, match=r"not a LoRR problem \(JSON\)"):
        read_problem(path)


def test_more_robots_than_the_agent_file_need_random_starts(tmp_path: Path) -> None:
    path = write_problem(tmp_path, "2\n1,7\n4,0\n")
    sim = build_sim(lorr_scenario(path, num_robots=3, horizon=20).spec())
    with pytest.raises(ConfigError, match=r"holds 2 start cells, sim\.num_robots=3; use tasks"):
        sim.reset(0)
    sim = build_sim(lorr_scenario(path, num_robots=3, starts="random", horizon=20).spec())
    sim.reset(0)
    assert len(np.unique(sim.robot_xy, axis=0)) == 3


@pytest.fixture
def kit() -> Path:
    if not RANDOM.is_file():
        pytest.skip(f"LoRR start kit not found at {KIT}")
    return RANDOM


def test_start_kit_problem_runs_collision_free_with_the_window(kit: Path) -> None:
    """The start kit's random 32x32 problem (100 robots): its starts, a window of 150
    revealed tasks, PIBT without conflicts, tasks finished by the horizon counted."""
    s = lorr_scenario(kit, horizon=300)
    assert (s.sim["num_robots"], s.sim["queue_len"], s.sim["horizon"]) == (100, 150, 300)
    assert lorr_scenario(kit).sim["horizon"] == LORR_HORIZON
    sim = build_sim(s.spec())
    problem = read_problem(kit)
    run_episode(sim, make_baseline("mpdm"), seed=0)
    schedule = sim.schedule()
    check_schedule(sim.layout, schedule)
    np.testing.assert_array_equal(
        schedule.positions[0], read_agents(problem.agents_path, problem.layout())
    )
    metrics = sim.metrics()
    assert metrics.tasks_finished == len(schedule.task_delivered) > 100
    assert (schedule.task_delivered <= 300).all()
    # The queue shows file order: the first 150 tasks were revealed at t = 0.
    first = read_lorr_tasks(problem.tasks_path, problem.layout())[:150]
    np.testing.assert_array_equal(sim.tasks[:150], first)


def test_dead_end_bonus_breaks_the_standoffs_rotation_was_for(kit: Path) -> None:
    """The start kit's random map, turn-free without guidance, where standoffs are most
    frequent: with fixed priorities alone it deadlocked (seed 0: no goal reached for 200
    timesteps by t = 508, before the dead-end bonus); with LoRR's dead-end bonus and no
    rotation (the default) it runs to the horizon, and with rotation too."""

    def play(patience: int | None) -> object:
        nav = {"name": "pibt", "stall_limit": 200, "patience": patience, "record": False,
               "turns": False, "guidance": 0.0}  # fmt: skip
        sim = build_sim(lorr_scenario(kit, horizon=700, navigator=nav).spec())
        run_episode(sim, make_baseline("mpdm"), seed=0)
        return sim

    fixed = play(None)
    assert fixed.metrics().tasks_finished > 2000
    assert fixed.executor.stats()["rotations"] == 0
    rotating = play(16)
    assert rotating.metrics().tasks_finished > 2000
    assert rotating.executor.stats()["rotations"] > 0


@pytest.mark.parametrize("group", ["sim", "env"], ids=["today", "before-sim-was-env"])
def test_throughput_table_reads_eval_results(group: str) -> None:
    """rtaw-eval's results of horizon episodes become the docs' table, with LoRR's
    published figures beside warehouse_large at 5,000 robots (results written before
    the simulator's keys were ``sim`` hold them as ``env``: the same table)."""
    from rtaw_marl.evaluation.throughput import throughput_markdown

    payload = {
        "config": {group: {"num_robots": 5000, "horizon": 3600}},
        "policies": {
            "mpdm": {"tasks_finished": [100.0, 110.0], "wall_time_s": [36.0, 36.0]},
            "batch": {"tasks_finished": [110.0, 121.0], "wall_time_s": [72.0, 72.0]},
        },
    }
    table = throughput_markdown([("warehouse_large, M=5,000", payload)])
    rows = table.splitlines()[2:]
    assert rows[0].startswith("| warehouse_large, M=5,000 | mpdm | 2 | 105 ± 64 | 0.0 | — | 10.0 |")
    assert "| batch | 2 | 116 ± 70 | 0.0 | +10.0% [+3.9, +16.1]* | 20.0 |" in rows[1]
    assert "67,177" in rows[2]
    assert "94,232" in rows[3]


def test_pettingzoo_env_takes_a_lorr_scenario(tmp_path: Path) -> None:
    """warehouse_v1.env(scenario=lorr_scenario(path)): MPDM acting on the env's own
    observations plays the episode act_sim plays."""
    from rtaw_marl import warehouse_v1

    path = write_problem(tmp_path, "4\n1,7\n4,0\n3,5\n7,1\n", teamSize=2)
    s = lorr_scenario(path, horizon=30)
    env = warehouse_v1.env(scenario=s)
    env.reset(seed=0)
    rule = make_baseline("mpdm", env=env)
    for _ in env.agent_iter():
        obs, _, term, trunc, _ = env.last()
        env.step(None if term or trunc else rule.act(obs))
    sim = build_sim(s.spec())
    run_episode(sim, make_baseline("mpdm"), seed=0)
    assert env.unwrapped.sim.metrics() == sim.metrics()
    assert sim.metrics().tasks_finished > 0


def test_eval_journal_digests_the_problem_and_its_files(tmp_path: Path) -> None:
    """rtaw-eval resume=true matches a LoRR setting by the contents of all four files."""
    from rtaw_marl.evaluation.journal import with_file_digests

    path = write_problem(tmp_path, "2\n1,7\n4,0\n")
    before = with_file_digests({"tasks": {"name": "lorr", "problem": str(path)}})
    (tmp_path / "t.tasks").write_text("2\n1,7\n5,0\n")
    after = with_file_digests({"tasks": {"name": "lorr", "problem": str(path)}})
    assert before["tasks"]["problem"][0] == after["tasks"]["problem"][0]  # the JSON
    assert before != after


def test_state_round_trip_keeps_the_owed_refills(tmp_path: Path) -> None:
    """With sim.refill=finish a freed robot's refill is owed until its next decision:
    a simulator that loads a mid-episode state plays the same rest of the episode."""
    path = write_problem(tmp_path, "4\n1,7\n4,0\n3,5\n7,1\n")
    spec = lorr_scenario(path, navigator="astar", horizon=40).spec()
    a, b = build_sim(spec), build_sim(spec)
    a.reset(0)
    b.reset(1)
    for _ in range(3):
        a.step(int(np.flatnonzero(a.queue_mask)[0]))
    b.load_state(a.state())
    for sim in (a, b):
        while not sim.done:
            sim.step(int(np.flatnonzero(sim.queue_mask)[0]))
    assert a.metrics() == b.metrics()
    assert a.metrics().tasks_served > 3
