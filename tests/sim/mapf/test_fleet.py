"""Collision-aware episodes (``sipp``, ``cbs`` executors): every schedule passes the checker.

Hand-made corridors, swaps and bottlenecks with known answers, blocked goals, deadlocks,
time limits and the CBS node budget, then hypothesis episodes on random small layouts.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rtaw_marl.errors import ConfigError, InvalidActionError, PlanningError, PlanningTimeout
from rtaw_marl.evaluation.evaluate import run_episode
from rtaw_marl.policies import make_baseline
from rtaw_marl.sim.builder import SimSpec, build_sim
from rtaw_marl.sim.config import SimConfig
from rtaw_marl.sim.core import WarehouseSim
from rtaw_marl.sim.distances import GridDistance
from rtaw_marl.sim.layout import Layout, open_grid
from rtaw_marl.sim.mapf import CBSExecutor, Schedule, SIPPExecutor, check_schedule
from rtaw_marl.sim.options import navigator_option
from rtaw_marl.sim.tasks import FixedTasks

pytestmark = pytest.mark.unit

PLANNERS = ["sipp", "cbs"]


def grid(*rows: str) -> Layout:
    """A layout from ASCII rows ('.' free, '@' blocked)."""
    return Layout(np.array([[c == "@" for c in row] for row in rows]))


def play(
    layout: Layout,
    navigator: str | dict,
    starts: list[tuple[int, int]],
    tasks: list[tuple[int, int, int, int]],
    actions: list[int] | None = None,
    queue_len: int = 1,
    **sim: object,
) -> tuple[WarehouseSim, Schedule]:
    """Serve ``tasks`` (first queued first, or by ``actions``); check the executed schedule."""
    config = SimConfig(
        num_robots=len(starts), num_tasks=len(tasks), queue_len=queue_len, noise_mean=0.0,
        noise_var=0.0, robot_starts=tuple(starts), **sim,
    )  # fmt: skip
    option = navigator_option(navigator)
    sim = WarehouseSim(config, layout, option.distance_model(layout), FixedTasks(tasks),
                       executor=option.executor())  # fmt: skip
    sim.reset(0)
    for i in range(len(tasks)):
        sim.step(actions[i] if actions else int(np.flatnonzero(sim.queue_mask)[0]))
    assert sim.done
    schedule = sim.schedule()
    check_schedule(layout, schedule, expected_tasks=len(tasks))
    return sim, schedule


@pytest.mark.parametrize("nav", PLANNERS)
def test_single_robot_times_are_shortest_paths(nav: str) -> None:
    """Alone on the grid a robot's TTD and completion are the A* distances."""
    layout = grid("......", "..@@..", "......")
    sim, schedule = play(layout, nav, [(0, 0)], [(5, 2, 0, 2), (2, 0, 5, 0)])
    # (0,0) -> (5,2): 7; -> (0,2): 5; then (0,2) -> (2,0): 4; -> (5,0): 3.
    assert schedule.task_ttd.tolist() == [7, 4]
    assert schedule.task_delivered.tolist() == [12, 19]
    assert sim.metrics().ttd == 11.0
    assert sim.metrics().makespan == 19.0


@pytest.mark.parametrize("nav", PLANNERS)
def test_swap_through_a_pocket(nav: str) -> None:
    """Two robots swap the ends of a corridor with a one-cell pocket above x = 3.

    Robot 0 (x=0) goes to x=6 and robot 1 (x=6) to x=0, 6 steps each alone. The one
    that dodges reaches the pocket at t=4 at the earliest, so the other passes x=3 at
    t=4 (delivered at 7) and the dodger comes back (8): 15 is optimal.
    """
    layout = grid("@@@.@@@", ".......")
    tasks = [(0, 1, 6, 1), (6, 1, 0, 1)]  # origins are the robots' own cells
    _, schedule = play(layout, nav, [(0, 1), (6, 1)], tasks, queue_len=2)
    assert schedule.task_ttd.tolist() == [0, 0]
    assert sorted(schedule.task_delivered.tolist()) == [7, 8]
    assert (schedule.positions == (3, 0)).all(axis=-1).any()


@pytest.mark.parametrize("nav", PLANNERS)
def test_bottleneck_door_one_at_a_time(nav: str) -> None:
    """Two rooms joined by a one-cell door: the robots pass it one after the other."""
    layout = grid("...@...", ".......", "...@...")
    # Both robots must cross the door (3, 1) from left to right.
    starts = [(2, 0), (2, 2)]
    tasks = [(4, 0, 6, 0), (4, 2, 6, 2)]
    _, schedule = play(layout, nav, starts, tasks, queue_len=2)
    door_times = [
        t for t in range(schedule.horizon + 1) for m in range(2)
        if tuple(schedule.positions[t, m]) == (3, 1)
    ]  # fmt: skip
    assert len(door_times) == len(set(door_times)) == 2
    # Alone each pickup takes 4 steps; sharing the door delays one robot by exactly 1.
    assert sorted(schedule.task_ttd.tolist()) == [4, 5]


@pytest.mark.parametrize("nav", PLANNERS)
def test_idle_robot_on_the_goal_is_moved_aside(nav: str) -> None:
    """The last task's destination is where an idle robot stands: it steps aside."""
    layout = open_grid(5, 3)
    sim, schedule = play(layout, nav, [(0, 1), (4, 1)], [(1, 1, 4, 1)])
    assert sim.executor.stats()["evacuations"] >= 1
    assert tuple(schedule.positions[-1, 0]) == (4, 1)
    assert tuple(schedule.positions[-1, 1]) != (4, 1)


@pytest.mark.parametrize("nav", PLANNERS)
def test_robot_waits_for_the_holder_of_its_goal(nav: str) -> None:
    """Mid-episode a goal held by a robot that will leave: the planner waits, no error.

    Robot 1 stands on task 0's destination; it gets task 1 right after (same time)
    and leaves, so robot 0 plans once robot 1 has moved, still at t=0: no delay.
    """
    layout = open_grid(6, 3)
    tasks = [(0, 0, 5, 1), (5, 1, 5, 0)]
    sim, schedule = play(layout, nav, [(0, 0), (5, 1)], tasks, queue_len=2)
    assert sim.executor.stats()["planning_calls"] > 2  # robot 0 could not plan at first
    assert schedule.task_delivered.tolist() == [6, 1]


@pytest.mark.parametrize("nav", PLANNERS)
def test_unsolvable_corridor_raises_a_clear_error(nav: str) -> None:
    """An idle robot in a dead-end corridor on the only route: PlanningError, no hang."""
    layout = open_grid(5, 1)
    with pytest.raises(PlanningError, match=r"deadlocked.*robot 0 .*task 0"):
        play(layout, nav, [(0, 0), (2, 0)], [(0, 0, 4, 0)])


@pytest.mark.parametrize("nav", PLANNERS)
def test_time_limit_error_names_the_setting(nav: str) -> None:
    """A planning call past navigator.time_limit stops the episode with PlanningTimeout."""
    with pytest.raises(PlanningTimeout, match=r"navigator.time_limit=1e-09"):
        play(open_grid(20, 20), {"name": nav, "time_limit": 1e-9}, [(0, 0)], [(19, 19, 0, 0)])


@pytest.mark.parametrize("nav", PLANNERS)
def test_config_errors(nav: str) -> None:
    """Completion noise, fractional start times and a bad time limit are refused."""
    layout = open_grid(4, 4)
    tasks = FixedTasks([(0, 0, 1, 1)])
    astar = GridDistance(layout)
    with pytest.raises(ConfigError, match=rf"navigator '{nav}' .*sim.noise_mean=0 sim.noise_var=0"):
        WarehouseSim(SimConfig(num_robots=1, num_tasks=1), layout, astar, tasks,
                     executor=navigator_option(nav).executor())  # fmt: skip
    config = SimConfig(num_robots=1, num_tasks=1, noise_mean=0, noise_var=0,
                       robot_free_times=(0.5,))  # fmt: skip
    with pytest.raises(ConfigError, match=r"whole-second sim.robot_free_times"):
        WarehouseSim(config, layout, astar, tasks, executor=navigator_option(nav).executor())
    for bad in (0, -1.0, True, "3"):
        with pytest.raises(ConfigError, match=r"navigator.time_limit must be a positive"):
            navigator_option({"name": nav, "time_limit": bad}).executor()
        with pytest.raises(ConfigError, match=r"navigator.time_limit must be a positive"):
            navigator_option({"name": nav, "time_limit": bad})
    with pytest.raises(ConfigError, match=r"unknown key navigator\.timelimit"):
        navigator_option({"name": nav, "timelimit": 3})
    sim = build_sim(SimSpec.of({"num_robots": 1, "num_tasks": 1}, layout, "astar", tasks))
    with pytest.raises(ConfigError, match=r"'astar' moves robots independently.*navigator=sipp"):
        sim.schedule()


def test_executor_parameters_are_explicit_and_checked() -> None:
    """No defaults in the executors; a bad max_nodes is refused; one executor per sim."""
    with pytest.raises(TypeError):
        SIPPExecutor()  # type: ignore[call-arg]
    with pytest.raises(TypeError):
        CBSExecutor(time_limit=1.0)  # type: ignore[call-arg]
    for bad in (0, 1.5, True):
        with pytest.raises(ConfigError, match=r"navigator.max_nodes must be a positive integer"):
            CBSExecutor(time_limit=1.0, max_nodes=bad)  # type: ignore[arg-type]
    layout = open_grid(4, 4)
    config = SimConfig(num_robots=1, num_tasks=1, noise_mean=0, noise_var=0)
    executor = SIPPExecutor(time_limit=1.0)
    assert (executor.name, executor.collision_aware) == ("sipp", True)
    sim = WarehouseSim(config, layout, GridDistance(layout), FixedTasks([(0, 0, 1, 1)]),
                       executor=executor)  # fmt: skip
    with pytest.raises(InvalidActionError, match="only when the episode is done"):
        sim.schedule()
    with pytest.raises(ConfigError, match="already belongs to a simulator"):
        WarehouseSim(config, layout, GridDistance(layout), FixedTasks([(0, 0, 1, 1)]),
                     executor=executor)  # fmt: skip


def test_registry_builds_astar_plus_the_executor_with_its_parameters() -> None:
    """``sipp``/``cbs`` specs: an A* distance model and the executor with exactly the values
    given."""
    keys = {"num_robots": 2, "num_tasks": 2, "noise_mean": 0.0, "noise_var": 0.0}
    sim = build_sim(
        SimSpec.of(keys, "open", {"name": "cbs", "time_limit": 1.5, "max_nodes": 7}, "random")
    )
    assert isinstance(sim.distance_model, GridDistance)
    assert isinstance(sim.executor, CBSExecutor)
    assert (sim.executor.time_limit, sim.executor.max_nodes) == (1.5, 7)
    assert sim.executor.fleet.max_nodes == 7
    sim = build_sim(SimSpec.of(keys, "open", "sipp", "random"))
    assert isinstance(sim.distance_model, GridDistance)
    assert isinstance(sim.executor, SIPPExecutor)
    assert sim.executor.time_limit == 10.0
    defaults = navigator_option("cbs").executor()
    assert (defaults.time_limit, defaults.max_nodes) == (10.0, 200)  # type: ignore[attr-defined]
    assert navigator_option("cbs").executor() is not defaults  # a fresh one per simulator


def test_cbs_node_budget_falls_back_and_counts() -> None:
    """With one high-level node the joint plan through a one-cell door is out of budget:
    the second robot plans alone around the first (a counted fallback), validly."""
    layout = grid("...@...", ".......", "...@...")
    starts, tasks = [(2, 0), (2, 2)], [(4, 0, 6, 0), (4, 2, 6, 2)]
    sim, schedule = play(layout, {"name": "cbs", "max_nodes": 1}, starts, tasks, queue_len=2)
    fleet = sim.executor.fleet
    assert (fleet.last_cbs.nodes, fleet.last_cbs.exhausted) == (1, "max_nodes")
    assert sim.executor.stats()["cbs_fallbacks"] == fleet.fallbacks == 1
    # The fallback still shares the door: one robot is delayed by exactly one step.
    assert sorted(schedule.task_ttd.tolist()) == [4, 5]


@pytest.mark.parametrize("nav", PLANNERS)
def test_warehouse_episode_is_valid_deterministic_and_consistent(nav: str) -> None:
    """A 60x60 MPDM episode: checker passes, same seed same schedule, TTDs add up."""
    keys = {"num_robots": 10, "num_tasks": 40, "noise_mean": 0.0, "noise_var": 0.0}
    runs = []
    for _ in range(2):
        sim = build_sim(SimSpec.of(keys, {"name": "preset", "preset": "C"}, nav, "designated"))
        run_episode(sim, make_baseline("mpdm"), seed=3)
        schedule = sim.schedule()
        check_schedule(sim.layout, schedule, expected_tasks=40)
        runs.append((sim, schedule))
    (sim, a), (_, b) = runs
    np.testing.assert_array_equal(a.positions, b.positions)
    assert (sim.executor.name, sim.executor.collision_aware) == (nav, True)
    assert set(sim.executor.stats()) == {"planning_calls", "evacuations", "cbs_fallbacks"}
    assert sim.executor.stats()["planning_calls"] >= 40
    assert sim.metrics().ttd == pytest.approx(float(a.task_ttd.sum()))
    assert sim.metrics().makespan == pytest.approx(float(a.task_delivered.max()))
    # Waits only ever add to the single-robot distances.
    astar = navigator_option("astar").distance_model(sim.layout)
    starts = a.positions[a.task_assigned, a.task_robot]
    assert (a.task_ttd >= astar.distance(starts, a.tasks[:, :2])).all()


#: Dense small cases that once deadlocked: two rooms joined by a one-cell corridor, and
#: idle robots trapped in a pocket on the only ways to a goal (found by hypothesis).
DENSE = [
    (("....@", "..@..", "..@..", "..@.."), [(0, 3), (0, 1), (3, 3), (3, 0)],
     [(0, 2, 3, 1), (4, 2, 1, 1), (4, 3, 3, 2), (0, 0, 4, 3)]),
    (("....@...", ".....@..", ".....@@.", "........"), [(1, 3), (3, 0), (6, 0), (4, 2), (1, 0)],
     [(3, 1, 0, 3), (6, 0, 5, 0), (6, 0, 4, 2), (7, 2, 6, 1), (7, 0, 1, 0), (4, 1, 7, 2),
      (6, 1, 3, 1), (4, 3, 0, 1), (2, 0, 5, 0)]),
    (("......", "......", "@...@@", ".@....", "......", "......"),
     [(3, 5), (4, 1), (4, 5), (4, 3)],
     [(3, 0, 5, 3), (3, 1, 5, 0), (5, 5, 5, 5), (3, 2, 0, 4), (3, 4, 1, 2), (1, 0, 4, 1),
      (5, 3, 5, 0)]),
]  # fmt: skip


@pytest.mark.parametrize("nav", PLANNERS)
@pytest.mark.parametrize("case", range(len(DENSE)))
def test_dense_small_cases_complete(nav: str, case: int) -> None:
    """Robots that block each other's only ways are moved aside; every task is delivered."""
    rows, starts, tasks = DENSE[case]
    sim, _ = play(grid(*rows), nav, starts, tasks, queue_len=2)
    assert sim.executor.stats()["evacuations"] >= 1


@st.composite
def scenarios(draw: st.DrawFn) -> tuple[Layout, list, list]:
    """A small random layout (one connected region), robots on distinct cells, tasks."""
    w, h = draw(st.integers(5, 8)), draw(st.integers(4, 7))
    rng = np.random.default_rng(draw(st.integers(0, 2**31)))
    obstacles = rng.random((h, w)) < draw(st.floats(0.0, 0.2))
    layout = Layout(obstacles) if not obstacles.all() else open_grid(w, h)
    cells = layout.main_cells
    m = draw(st.integers(1, min(4, len(cells) // 4)))
    starts = [tuple(c) for c in cells[rng.choice(len(cells), m, replace=False)].tolist()]
    k = draw(st.integers(1, 8))
    picks = rng.integers(0, len(cells), size=(k, 2))
    tasks = [(*cells[o].tolist(), *cells[d].tolist()) for o, d in picks]
    return layout, starts, tasks


@pytest.mark.parametrize("nav", PLANNERS)
@settings(max_examples=40, deadline=None, database=None, derandomize=True)
@given(scenario=scenarios())
def test_random_small_layouts_complete_without_conflicts(nav: str, scenario: tuple) -> None:
    """Any small connected layout with room to spare: every task is delivered, no conflict."""
    layout, starts, tasks = scenario
    play(layout, nav, starts, tasks, queue_len=2)


def test_all_robots_blocked_is_a_planning_error_not_infinite_time() -> None:
    """Regression: when every robot was deferred, one partial resolve could leave the
    next robot selected at t=inf, and the next step crashed with OverflowError."""
    keys = {"num_robots": 3, "num_tasks": 5, "queue_len": 3, "noise_mean": 0, "noise_var": 0,
           "robot_starts": [[1, 0], [2, 1], [0, 1]], "robot_free_times": [0, 3, 2]}  # fmt: skip
    tasks = FixedTasks([[0, 1, 1, 1], [2, 0, 2, 1], [0, 0, 2, 0], [0, 1, 1, 1], [2, 0, 2, 1]])
    sim = build_sim(SimSpec.of(keys, {"name": "open", "width": 3, "height": 2}, "sipp", tasks))
    sim.reset(0)
    for action in [1, 0, 2, 0]:
        sim.step(action)
        assert sim.time < float("inf")
    with pytest.raises(PlanningError, match="deadlocked"):
        sim.step(1)
