"""LoRR's action model in lifelong PIBT (``navigator.turns=true``): headings, quarter
turns, forward moves cancelled behind a robot that does not move forward."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rtaw_marl.errors import ConfigError, ScheduleError
from rtaw_marl.evaluation.evaluate import run_episode
from rtaw_marl.policies import make_baseline
from rtaw_marl.sim.builder import SimSpec, build_sim
from rtaw_marl.sim.config import SimConfig
from rtaw_marl.sim.core import WarehouseSim
from rtaw_marl.sim.layout import Layout, open_grid
from rtaw_marl.sim.mapf import check_schedule
from rtaw_marl.sim.mapf._pibt import bfs_compact, compact_graph
from rtaw_marl.sim.mapf._turns import FORWARD, TURN_CCW, TURN_CW, WAIT, turn_step
from rtaw_marl.sim.options import navigator_option
from rtaw_marl.sim.tasks import FixedTasks
from tests.sim.mapf.conftest import random_fleet

pytestmark = pytest.mark.unit


def play(
    layout: Layout, starts: list[tuple[int, int]], tasks: list[tuple[int, int, int, int]],
    queue_len: int = 1, seed: int = 0,
) -> WarehouseSim:  # fmt: skip
    """Serve ``tasks`` first queued first with turning robots; check the schedule."""
    config = SimConfig(
        num_robots=len(starts), num_tasks=len(tasks), queue_len=queue_len, noise_mean=0.0,
        noise_var=0.0, robot_starts=tuple(starts),
    )  # fmt: skip
    option = navigator_option({"name": "pibt", "turns": True, "guidance": 0.0})
    sim = WarehouseSim(config, layout, option.distance_model(layout), FixedTasks(tasks),
                       executor=option.executor())  # fmt: skip
    sim.reset(seed)
    while not sim.done:
        sim.step(int(np.flatnonzero(sim.queue_mask)[0]))
    check_schedule(layout, sim.schedule(), expected_tasks=len(tasks))
    return sim


@pytest.mark.parametrize(
    ("origin", "turns"),
    [((4, 0), 0), ((0, 3), 1), ((0, 0), 0)],  # east: none; south: one quarter; here
)
def test_a_lone_robot_pays_one_timestep_per_quarter_turn(origin, turns) -> None:
    """Starting east at (0, 0): the pickup takes the distance plus one timestep per
    quarter turn on the way."""
    sim = play(open_grid(6, 4), [(0, 0)], [(*origin, 5, 3)])
    schedule = sim.schedule()
    assert schedule.task_ttd.tolist() == [origin[0] + origin[1] + turns]
    assert schedule.headings[0].tolist() == [0]
    assert sim.executor.stats()["turn_actions"] >= turns


@pytest.mark.parametrize("seed", range(5))
def test_on_a_staircase_a_robot_goes_straight_then_turns_once(seed: int) -> None:
    """From (0, 0) facing east to (3, 3) on an open grid, east and south are equally
    near at every step: the robot keeps going the way it faces (the kit's tie-break), so
    the walk costs the distance and a single turn, whatever the random tie-breaks."""
    sim = play(open_grid(5, 5), [(0, 0)], [(3, 3, 3, 3)], seed=seed)
    assert sim.schedule().task_ttd.tolist() == [6 + 1]
    assert sim.executor.stats()["turn_actions"] == 1


def test_a_half_turn_takes_two_timesteps() -> None:
    """Facing east, the origin due west: two quarter turns (clockwise, as the kit), then
    the walk; the robot arrives facing west."""
    sim = play(open_grid(6, 1), [(3, 0)], [(0, 0, 0, 0)])
    schedule = sim.schedule()
    assert schedule.task_ttd.tolist() == [3 + 2]
    assert schedule.headings[:3, 0].tolist() == [0, 1, 2]
    assert schedule.headings[-1, 0] == 2


def test_a_forward_move_behind_a_turning_robot_waits() -> None:
    """Two robots in a row facing east; the front one must turn south: it turns, and the
    one behind, though PIBT planned it into the front one's cell, waits (no collision)."""
    index, cells, nbr = compact_graph(open_grid(3, 2).obstacles)
    pos = np.array([index[0, 0], index[0, 1]], dtype=np.int64)  # (x=0, y=0), (x=1, y=0)
    heading = np.array([0, 0], dtype=np.int64)
    goals = [index[0, 2], index[1, 1]]  # robot 0 east to (2, 0); robot 1 south to (1, 1)
    fields = np.empty((2, len(cells)), dtype=np.int32)
    for r, g in enumerate(goals):
        bfs_compact(nbr, int(g), fields[r])
    occ_now = np.full(len(cells), -1, dtype=np.int64)
    occ_now[pos] = [0, 1]
    occ_next = np.full(len(cells), -1, dtype=np.int64)
    target = np.full(2, -1, dtype=np.int64)
    nxt, action = np.empty(2, dtype=np.int64), np.empty(2, dtype=np.int64)
    order = np.array([1, 0], dtype=np.int64)
    turn_step(pos, heading, target, order, np.arange(2), fields, nbr, np.zeros((2, 5)),
              occ_now, occ_next, nxt, action)  # fmt: skip
    assert action.tolist() == [WAIT, TURN_CW]  # robot 0 planned into (1, 0): cancelled
    assert pos.tolist() == [index[0, 0], index[0, 1]]
    assert heading.tolist() == [0, 1]
    assert target.tolist() == [index[0, 1], index[1, 1]]  # both keep their next cells
    turn_step(pos, heading, target, order, np.arange(2), fields, nbr, np.zeros((2, 5)),
              occ_now, occ_next, nxt, action)  # fmt: skip
    assert action.tolist() == [FORWARD, FORWARD]  # a chain: both move at once
    assert pos.tolist() == [index[0, 1], index[1, 1]]
    assert (occ_next == -1).all()
    assert (occ_now[pos] == [0, 1]).all()


@settings(max_examples=30, deadline=None, database=None, derandomize=True)
@given(seed=st.integers(0, 2**31), fill=st.floats(0.05, 0.9))
def test_turn_step_never_collides_on_random_grids(seed: int, fill: float) -> None:
    """Random obstacles, robots and goals: forty timesteps keep distinct cells, no swaps,
    forward moves only the way a robot faces, and at most a quarter turn when it stays."""
    f = random_fleet(seed, fill)
    if f is None:
        return
    rng, m, pos, nbr, occ_now, occ_next = f.rng, f.m, f.pos, f.nbr, f.occ_now, f.occ_next
    heading = rng.integers(0, 4, m).astype(np.int64)
    target = np.full(m, -1, dtype=np.int64)
    action = np.empty(m, dtype=np.int64)
    forward = np.array([[1, 0], [0, 1], [-1, 0], [0, -1]])
    for _ in range(40):
        before, facing = pos.copy(), heading.copy()
        order = rng.permutation(m).astype(np.int64)
        turn_step(pos, heading, target, order, f.goal_field, f.fields, nbr, rng.random((m, 5)),
                  occ_now, occ_next, f.nxt, action)  # fmt: skip
        assert len(np.unique(pos)) == m
        moved = pos != before
        assert (action[moved] == FORWARD).all()
        assert (f.cells[pos[moved]] - f.cells[before[moved]] == forward[facing[moved]]).all()
        where = {int(c): i for i, c in enumerate(before)}
        for i in np.flatnonzero(moved):
            j = where.get(int(pos[i]))
            assert j is None or pos[j] != before[i], "swap conflict"
        turned = (heading - facing) % 4
        assert (turned[moved] == 0).all()
        assert np.isin(turned[~moved], [0, 1, 3]).all()
        assert ((turned == 1) == (action == TURN_CW)).all()
        assert ((turned == 3) == (action == TURN_CCW)).all()
        assert (occ_next == -1).all()
        assert (occ_now[pos] == np.arange(m)).all()


def warehouse(turns: bool) -> WarehouseSim:
    sim = {"num_robots": 60, "num_tasks": 200, "queue_len": 10}
    nav = {"name": "pibt", "turns": turns, "guidance": 0.0}
    return build_sim(SimSpec.of(sim, {"name": "preset", "preset": "C"}, nav, "designated"))


def test_a_warehouse_episode_with_turns_is_valid_deterministic_and_slower() -> None:
    """60 robots on layout C: the checker (headings included) passes, the same seed
    gives the same moves, and turning costs time against the turn-free model."""
    runs = []
    for _ in range(2):
        sim = warehouse(turns=True)
        run_episode(sim, make_baseline("mpdm"), seed=4)
        schedule = sim.schedule()
        check_schedule(sim.layout, schedule, expected_tasks=200)
        runs.append((sim, schedule))
    (sim, a), (_, b) = runs
    np.testing.assert_array_equal(a.positions, b.positions)
    np.testing.assert_array_equal(a.headings, b.headings)
    assert sim.executor.stats()["turn_actions"] > 0
    free = warehouse(turns=False)
    run_episode(free, make_baseline("mpdm"), seed=4)
    assert free.schedule().headings is None
    assert "turn_actions" not in free.executor.stats()
    assert sim.metrics().ttd > free.metrics().ttd


def test_the_checker_catches_sideways_moves_and_half_turns() -> None:
    sim = warehouse(turns=True)
    run_episode(sim, make_baseline("mpdm"), seed=1)
    good = sim.schedule()
    moving = np.flatnonzero((good.positions[1:] != good.positions[:-1]).any(-1).any(0))
    robot = int(moving[0])
    t = int(np.flatnonzero((good.positions[1:, robot] != good.positions[:-1, robot]).any(-1))[0])
    sideways = good.headings.copy()
    sideways[t, robot] = (sideways[t, robot] + 1) % 4
    with pytest.raises(ScheduleError, match=f"robot {robot} moves from t={t} to t={t + 1}"):
        check_schedule(sim.layout, dataclasses.replace(good, headings=sideways))
    # A heading flipped at one time where the robot waits before and after: two half turns.
    waits = (good.positions[1:] == good.positions[:-1]).all(-1)[:, robot]
    waits &= good.headings[1:, robot] == good.headings[:-1, robot]
    s = int(np.flatnonzero(waits[:-1] & waits[1:])[0])
    half = good.headings.copy()
    half[s + 1, robot] = (half[s + 1, robot] + 2) % 4
    with pytest.raises(ScheduleError, match=f"robot {robot} turns a half turn from t={s}"):
        check_schedule(sim.layout, dataclasses.replace(good, headings=half))
    bad = good.headings.copy()
    bad[0, 0] = 7
    with pytest.raises(ScheduleError, match="robot 0 at t=0 has heading 7"):
        check_schedule(sim.layout, dataclasses.replace(good, headings=bad))


def test_turns_must_be_a_boolean() -> None:
    with pytest.raises(ConfigError, match=r"navigator\.turns must be true or false, got 'yes'"):
        navigator_option({"name": "pibt", "turns": "yes"})


def test_an_episode_with_turns_round_trips_through_lorr_format(tmp_path) -> None:
    """Written as LoRR writes its own runs (MAPF_T: headings, F/R/C/W) and read back by
    the one reader of the format: the same cells and headings at every timestep and the
    same tasks finished."""
    import json

    from rtaw_marl.integrations.lorr.output import read_replay, write_episode
    from rtaw_marl.viz.schedule_file import read_schedule_file

    sim = warehouse(turns=True)
    run_episode(sim, make_baseline("mpdm"), seed=2)
    schedule = sim.schedule()
    path = write_episode(schedule, tmp_path / "episode.json")
    data = json.loads(path.read_text())
    assert data["actionModel"] == "MAPF_T"
    assert {s[2] for s in data["start"]} == {"E"}
    letters = set(",".join(data["actualPaths"]).split(","))
    assert letters <= {"F", "R", "C", "W"}
    assert {"F", "R", "C"} <= letters
    back = read_schedule_file(path, sim.layout).schedule
    np.testing.assert_array_equal(back.positions, schedule.positions)
    np.testing.assert_array_equal(back.headings, schedule.headings)
    assert read_replay(path, sim.layout).tasks_finished == sim.metrics().tasks_finished
