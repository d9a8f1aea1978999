"""Lifelong PIBT execution (``navigator=pibt``, the turn-free model without guidance:
``test_turns.py`` and ``test_guidance.py`` test those), fixed-horizon episodes and LoRR's
reveal window (``sim.refill=finish``)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rtaw_marl.errors import ConfigError, PlanningError
from rtaw_marl.evaluation.evaluate import run_episode
from rtaw_marl.policies import make_baseline
from rtaw_marl.sim.builder import SimSpec, build_sim
from rtaw_marl.sim.config import SimConfig
from rtaw_marl.sim.core import WarehouseSim
from rtaw_marl.sim.layout import Layout, open_grid
from rtaw_marl.sim.mapf import check_schedule
from rtaw_marl.sim.mapf._pibt import bfs_compact, compact_graph, pibt_step
from rtaw_marl.sim.options import navigator_option
from rtaw_marl.sim.tasks import FixedTasks
from tests.sim.mapf.conftest import random_fleet

pytestmark = pytest.mark.unit


def grid(*rows: str) -> Layout:
    """A layout from ASCII rows ('.' free, '@' blocked)."""
    return Layout(np.array([[c == "@" for c in row] for row in rows]))


def play(
    layout: Layout,
    starts: list[tuple[int, int]],
    tasks: list[tuple[int, int, int, int]],
    queue_len: int = 1,
    stall_limit: int = 10_000,
) -> WarehouseSim:
    """Serve ``tasks`` first queued first with PIBT; check the executed schedule."""
    config = SimConfig(
        num_robots=len(starts), num_tasks=len(tasks), queue_len=queue_len, noise_mean=0.0,
        noise_var=0.0, robot_starts=tuple(starts),
    )  # fmt: skip
    option = navigator_option(
        {"name": "pibt", "stall_limit": stall_limit, "turns": False, "guidance": 0.0}
    )
    sim = WarehouseSim(config, layout, option.distance_model(layout), FixedTasks(tasks),
                       executor=option.executor())  # fmt: skip
    sim.reset(0)
    while not sim.done:
        sim.step(int(np.flatnonzero(sim.queue_mask)[0]))
    check_schedule(layout, sim.schedule(), expected_tasks=len(tasks))
    return sim


def test_compact_graph_and_bfs_match_the_grid() -> None:
    """Compact ids, 4-neighbours and BFS distances around a wall."""
    layout = grid("...", ".@.", "...")
    index, cells, nbr = compact_graph(layout.obstacles)
    assert index[1, 1] == -1
    assert len(cells) == 8
    assert (index[cells[:, 1], cells[:, 0]] == np.arange(8)).all()
    out = np.empty(8, dtype=np.int32)
    bfs_compact(nbr, int(index[0, 0]), out)
    assert [out[index[2, 2]], out[index[0, 2]], out[index[1, 2]]] == [4, 2, 3]


def test_single_robot_ttd_is_the_shortest_path() -> None:
    """Alone, a robot walks its BFS path: TTD is the distance to the origin, and it is
    free at the delivery."""
    sim = play(open_grid(6, 4), [(0, 0)], [(5, 0, 5, 3), (0, 3, 0, 0)])
    schedule = sim.schedule()
    assert schedule.task_ttd.tolist() == [5, 5]
    assert schedule.task_delivered.tolist() == [8, 16]


def test_oncoming_robots_pass_in_a_two_wide_corridor() -> None:
    """Four robots swapping the ends of a two-wide corridor (every edge on a cycle, where
    PIBT reaches every goal): no conflict, all delivered, at most a few steps of delay."""
    starts = [(0, 0), (0, 1), (7, 0), (7, 1)]
    tasks = [(7, 0, 7, 0), (7, 1, 7, 1), (0, 0, 0, 0), (0, 1, 0, 1)]
    sim = play(open_grid(8, 2), starts, tasks, queue_len=4)
    ttd = sim.schedule().task_ttd
    assert (ttd >= 7).all()
    assert ttd.max() <= 7 + 6


def test_one_wide_corridor_swap_is_a_clear_deadlock_error() -> None:
    """Two robots swapping ends of a one-wide corridor cannot pass: PlanningError after
    the stall limit, not an endless loop."""
    with pytest.raises(PlanningError, match="no robot reached its goal in 30 timesteps"):
        play(open_grid(5, 1), [(0, 0), (4, 0)], [(4, 0, 4, 0), (0, 0, 0, 0)], 2, 30)


def step_is_conflict_free(before: np.ndarray, after: np.ndarray, nbr: np.ndarray) -> None:
    assert len(np.unique(after)) == len(after), "vertex conflict"
    moved = before != after
    assert all(after[i] in nbr[before[i]] for i in np.flatnonzero(moved)), "not a move"
    where = {int(c): i for i, c in enumerate(before)}
    for i in np.flatnonzero(moved):
        j = where.get(int(after[i]))
        assert j is None or after[j] != before[i], "swap conflict"


@settings(max_examples=30, deadline=None, database=None, derandomize=True)
@given(seed=st.integers(0, 2**31), fill=st.floats(0.05, 0.9))
def test_pibt_step_never_collides_on_random_grids(seed: int, fill: float) -> None:
    """Random obstacles, robots on a random share of the cells, random goals: twenty
    timesteps of pibt_step keep distinct cells, legal moves and no swaps."""
    f = random_fleet(seed, fill)
    if f is None:
        return
    for _ in range(20):
        before = f.pos.copy()
        order = f.rng.permutation(f.m).astype(np.int64)
        pibt_step(f.pos, order, f.goal_field, f.fields, f.nbr, f.rng.random((f.m, 5)),
                  f.occ_now, f.occ_next, f.nxt)  # fmt: skip
        step_is_conflict_free(before, f.pos, f.nbr)
        assert (f.occ_next == -1).all()
        assert (f.occ_now[f.pos] == np.arange(f.m)).all()


def warehouse(**sim: object) -> WarehouseSim:
    base = {"num_robots": 60, "num_tasks": 200, "queue_len": 10}
    base.update(sim)
    nav = {"name": "pibt", "turns": False, "guidance": 0.0}  # the turn-free model
    return build_sim(SimSpec.of(base, {"name": "preset", "preset": "C"}, nav, "designated"))


def test_warehouse_episode_is_valid_and_deterministic() -> None:
    """60 robots on layout C: the checker passes, the same seed gives the same moves,
    and TTD adds up from the schedule."""
    runs = []
    for _ in range(2):
        sim = warehouse()
        run_episode(sim, make_baseline("mpdm"), seed=4)
        schedule = sim.schedule()
        check_schedule(sim.layout, schedule, expected_tasks=200)
        runs.append((sim, schedule))
    (sim, a), (_, b) = runs
    np.testing.assert_array_equal(a.positions, b.positions)
    assert sim.metrics().ttd == pytest.approx(float(a.task_ttd.sum()))
    assert sim.metrics().tasks_finished == 200
    stats = sim.executor.stats()
    assert stats["timesteps"] == len(a.positions) - 1
    assert 0 < stats["field_searches"] <= 400  # one per distinct goal cell at most


def test_horizon_episode_counts_tasks_finished_by_the_horizon() -> None:
    """episode_mode=horizon stops at T: the delivered tasks are those with a delivery
    time <= T, TTD is censored at T and the makespan is T."""
    sim = warehouse(episode_mode="horizon", horizon=150, num_tasks=10_000)
    run_episode(sim, make_baseline("mpdm"), seed=0)
    metrics = sim.metrics()
    finished = sim.task_finished[sim.task_robot >= 0]
    assert metrics.tasks_finished == int((finished <= 150).sum())
    assert 0 < metrics.tasks_finished < metrics.tasks_served < 10_000
    assert metrics.makespan == 150.0
    waits = sim.task_assigned[sim.task_robot >= 0] + sim.task_ttd[sim.task_robot >= 0]
    assert (waits <= 150 + 1e-9).all()
    assert sim.time <= 150 + 1e-9
    assert sim.truncated


def test_refill_on_finish_keeps_the_reveal_window() -> None:
    """sim.refill=finish: at every decision, revealed-and-unfinished tasks (queued or in
    progress) never exceed N, and a new task appears only once one is delivered."""
    sim = warehouse(num_robots=20, queue_len=30, refill="finish", num_tasks=120)
    sim.reset(1)
    while not sim.done:
        in_progress = int(((sim.task_robot >= 0) & (sim.task_finished > sim.time)).sum())
        assert int(sim.queue_mask.sum()) + in_progress <= 30
        sim.step(int(np.flatnonzero(sim.queue_mask)[0]))
    assert sim.metrics().tasks_served == 120


def test_config_errors_name_the_problem() -> None:
    with pytest.raises(ConfigError, match=r"sim\.episode_mode=horizon needs sim\.horizon"):
        SimConfig(episode_mode="horizon")
    with pytest.raises(ConfigError, match=r"sim\.refill=finish needs sim\.queue_len > sim\.num"):
        SimConfig(num_robots=10, queue_len=10, refill="finish")
    with pytest.raises(ConfigError, match=r"sim\.refill must be one of assign, finish"):
        SimConfig(refill="later")
    with pytest.raises(ConfigError, match=r"navigator\.stall_limit must be a positive integer"):
        navigator_option({"name": "pibt", "stall_limit": 0}).executor()
    with pytest.raises(ConfigError, match="two start together"):
        play(open_grid(4, 4), [(0, 0), (0, 0)], [(1, 1, 2, 2)])


def test_free_robots_are_the_idle_ones_not_those_past_their_planned_time() -> None:
    """Under traffic a robot is busy past its planned free time: sim.free_robots() lists
    the robots the executor has freed, which the batch rule matches."""
    sim = warehouse(num_robots=60, num_tasks=150)
    sim.reset(2)
    late = 0
    while not sim.done:
        free = sim.free_robots()
        assert (sim.executor.phase[free] == 0).all()
        late += int(((sim.robot_free_at <= sim.time) & (sim.executor.phase != 0)).sum())
        sim.step(int(np.flatnonzero(sim.queue_mask)[0]))
    assert late > 0  # the planned times alone would have counted busy robots
