"""The event-driven simulator: the paper's PoC, episode modes, validation, seeding and metrics."""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable

import numpy as np
import pytest

from rtaw_marl.errors import ConfigError, InvalidActionError, LayoutError
from rtaw_marl.policies import MPDM, RBTS, RandomPolicy
from rtaw_marl.policies.baselines import BaselinePolicy
from rtaw_marl.sim.builder import SimSpec, build_sim
from rtaw_marl.sim.config import SimConfig
from rtaw_marl.sim.core import WarehouseSim
from rtaw_marl.sim.distances import EuclideanDistance, GridDistance
from rtaw_marl.sim.layout import Layout, open_grid
from rtaw_marl.sim.tasks import TWO_TASKS, FixedTasks, RandomTasks

pytestmark = pytest.mark.unit

SQRT18 = math.sqrt(18.0)


def run(sim: WarehouseSim, policy: BaselinePolicy, seed: int) -> tuple[list[int], list[float]]:
    """Play one episode with ``policy`` (tie-breaking seeded by ``seed``); actions and rewards."""
    sim.reset(seed)
    policy.reset(seed)
    actions, rewards = [], []
    while not sim.done:
        action = policy.act_sim(sim)
        actions.append(action)
        rewards.append(sim.step(action))
    return actions, rewards


def small_sim(**overrides: object) -> WarehouseSim:
    """A 3-robot, 30-task random-task episode on a 12x12 open grid with the direct navigator."""
    values: dict[str, object] = {"num_robots": 3, "num_tasks": 30, "queue_len": 4}
    values.update(overrides)
    return build_sim(
        SimSpec.of(values, {"name": "open", "width": 12, "height": 12}, "direct", "random")
    )


# ----------------------------------------------------------------- the paper's PoC


def test_poc_mpdm_golden(poc_sim: Callable[..., WarehouseSim]) -> None:
    """MPDM on the PoC: TTD 22.737 (paper 22.69), tasks served in order 2,3,4,5,1 (1-based),
    with the queue and decision times of the appendix."""
    sim = poc_sim()
    policy = MPDM()
    sim.reset(0)
    policy.reset(0)
    robots, times, served, queues = [], [], [], []
    total = 0.0
    while not sim.done:
        queues.append(sim.queue_ids.tolist())
        robots.append(sim.robot)
        times.append(sim.time)
        slot = policy.act_sim(sim)
        served.append(int(sim.queue_ids[slot]) + 1)
        total -= sim.step(slot)
    assert total == pytest.approx(22.737, abs=0.01)
    assert sim.metrics().ttd == pytest.approx(total, rel=1e-12)
    assert served == [2, 3, 4, 5, 1]
    # 0-based task ids per slot: task 1 waits in slot 0 while slot 1 is refilled.
    assert queues == [[0, 1], [0, 2], [0, 3], [0, 4], [0, -1]]
    assert robots == [0, 1, 0, 1, 0]
    # Robot 0 at (2,2) takes (4,4)->(0,0): free at sqrt(8) + sqrt(32) = 8.485.
    assert times[:3] == pytest.approx([0.0, 2.0, math.sqrt(8) + math.sqrt(32)], abs=1e-9)
    assert sim.queue_mask.tolist() == [False, False]


def test_poc_rbts_golden(poc_sim: Callable[..., WarehouseSim]) -> None:
    """RBTS on the PoC: TTD 18.463 (paper 18.46), serving tasks 1,2,4,3,5 (1-based)."""
    sim = poc_sim()
    actions, rewards = run(sim, RBTS(), 0)
    assert -sum(rewards) == pytest.approx(18.463, abs=0.01)
    order = np.argsort(sim.task_assigned, kind="stable") + 1
    assert order.tolist() == [1, 2, 4, 3, 5]
    assert len(actions) == 5


def test_poc_exhaustive_optimum(poc_sim: Callable[..., WarehouseSim]) -> None:
    """Brute force over all 2^5 action sequences: 16 are legal, the optimum TTD is 17.936, and
    MPDM and RBTS are no better than it."""
    sim = poc_sim()
    totals: dict[tuple[int, ...], float] = {}
    illegal = 0
    for seq in itertools.product((0, 1), repeat=5):
        sim.reset(0)
        total = 0.0
        try:
            for action in seq:
                total -= sim.step(action)
        except InvalidActionError:
            illegal += 1
            continue
        assert sim.done
        totals[seq] = total
    assert len(totals) == 16
    assert illegal == 16
    best = min(totals, key=totals.__getitem__)
    assert totals[best] == pytest.approx(17.936, abs=0.01)
    assert best == (0, 0, 0, 1, 0)
    mpdm = -sum(run(poc_sim(), MPDM(), 0)[1])
    rbts = -sum(run(poc_sim(), RBTS(), 0)[1])
    assert totals[best] < rbts < mpdm
    assert max(totals.values()) >= mpdm


# ----------------------------------------------------------------- episode modes


def test_drain_mode_serves_exactly_num_tasks() -> None:
    """Drain mode serves every task once; the last decisions see the queue emptying (masked
    slots) and the episode terminates rather than truncates."""
    sim = small_sim(num_tasks=23, queue_len=5)
    sim.reset(4)
    policy = RandomPolicy()
    policy.reset(4)
    valid = []
    while not sim.done:
        valid.append(int(sim.queue_mask.sum()))
        assert (sim.queue_ids[sim.queue_mask] >= 0).all()
        assert (sim.queue_ids[~sim.queue_mask] == -1).all()
        assert (sim.queue_tasks()[~sim.queue_mask] == 0).all()
        sim.step(policy.act_sim(sim))
    assert valid == [5] * 19 + [4, 3, 2, 1]
    assert not sim.truncated
    assert not sim.queue_mask.any()
    metrics = sim.metrics()
    assert metrics.tasks_served == 23
    assert metrics.decisions == 23
    assert len(sim.tasks) == 23
    assert (sim.task_robot >= 0).all()
    assert sorted(np.unique(sim.task_robot).tolist()) == [0, 1, 2]


def test_drain_mode_with_fewer_tasks_than_slots() -> None:
    """With num_tasks < queue_len the extra slots are empty from the start."""
    sim = small_sim(num_tasks=2, queue_len=4)
    sim.reset(0)
    assert sim.queue_mask.tolist() == [True, True, False, False]
    with pytest.raises(InvalidActionError, match="empty queue slot"):
        sim.step(3)
    sim.step(1)
    sim.step(0)
    assert sim.done
    assert sim.metrics().tasks_served == 2


def test_paper_mode_keeps_queue_full_and_truncates() -> None:
    """Paper mode takes num_tasks decisions with a full queue; queued tasks stay unserved and
    the episode is truncated."""
    sim = small_sim(num_tasks=20, queue_len=5, episode_mode="paper")
    sim.reset(1)
    policy = MPDM()
    policy.reset(1)
    while not sim.done:
        assert sim.queue_mask.all()
        sim.step(policy.act_sim(sim))
    assert sim.truncated
    assert sim.queue_mask.all()
    assert len(sim.tasks) == 25
    assert int((sim.task_robot >= 0).sum()) == 20
    assert set(sim.queue_ids.tolist()) == set(np.flatnonzero(sim.task_robot < 0).tolist())
    assert sim.metrics().tasks_served == 20


def test_two_task_setting_always_task_a() -> None:
    """Two-task setting (paper mode, 10 robots, 10x10, direct): the queue always holds tasks
    A and B; always picking A costs each robot its start -> (0,0) once, then sqrt(18) each
    time, i.e. about 500*sqrt(18)."""
    sim = build_sim(
        SimSpec.of(
            {"num_robots": 10, "num_tasks": 500, "queue_len": 2, "episode_mode": "paper"},
            {"name": "open", "width": 10, "height": 10},
            "direct",
            "two_task",
        )
    )
    sim.reset(5)
    total = 0.0
    while not sim.done:
        rows = sim.queue_tasks().tolist()
        assert sorted(map(tuple, rows)) == sorted(TWO_TASKS)
        slot = rows.index(list(TWO_TASKS[0]))
        total -= sim.step(slot)
    starts = sim.robot_start_xy
    expected = float(np.hypot(starts[:, 0], starts[:, 1]).sum()) + 490 * SQRT18
    assert total == pytest.approx(expected, rel=1e-9)
    assert abs(total - 500 * SQRT18) < 10 * math.hypot(9, 9)
    assert sim.truncated
    assert sim.metrics().tasks_served == 500
    assert (sim.robot_xy == (3, 3)).all()


def test_two_task_needs_queue_of_two() -> None:
    """The two-task stream refills each slot with its own task, so queue_len must be 2."""
    with pytest.raises(ConfigError, match="queue_len must be 2"):
        build_sim(SimSpec.of({"num_robots": 2, "queue_len": 3}, "open", "direct", "two_task"))


# ----------------------------------------------------------------- invalid input


@pytest.mark.parametrize(
    ("action", "match"),
    [
        (-1, "not a queue slot"),
        (3, "not a queue slot"),
        (0.5, "integer slot index"),
        (1.0, "integer slot index"),
        (float("inf"), "integer slot index"),
        (True, "integer slot index"),
        ("x", "integer slot index"),
        (None, "integer slot index"),
    ],
)
def test_invalid_actions(action: object, match: str) -> None:
    """Out-of-range, fractional and non-numeric actions raise InvalidActionError and leave the
    state unchanged."""
    sim = small_sim(queue_len=3)
    sim.reset(0)
    before = (sim.decisions, sim.robot, sim.time, sim.queue_ids.copy())
    with pytest.raises(InvalidActionError, match=match):
        sim.step(action)  # type: ignore[arg-type]
    assert (sim.decisions, sim.robot, sim.time) == before[:3]
    assert np.array_equal(sim.queue_ids, before[3])
    sim.step(np.int64(2))
    assert sim.decisions == 1


def test_invalid_action_on_empty_slot_and_after_done(poc_sim: Callable[..., WarehouseSim]) -> None:
    """An empty slot and any step after the episode ended raise InvalidActionError."""
    sim = poc_sim()
    with pytest.raises(InvalidActionError, match="episode is over"):
        sim.step(0)  # never reset
    sim.reset(0)
    for action in (1, 1, 1, 1):
        sim.step(action)
    assert sim.queue_mask.tolist() == [True, False]
    with pytest.raises(InvalidActionError, match="action 1 names an empty queue slot"):
        sim.step(1)
    sim.step(0)
    assert sim.done
    with pytest.raises(InvalidActionError, match="episode is over"):
        sim.step(0)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"num_robots": 0}, "num_robots must be >= 1"),
        ({"queue_len": 0}, "queue_len must be >= 1"),
        ({"num_tasks": -3}, "num_tasks must be >= 1"),
        ({"num_robots": 2.5}, "num_robots must be an integer"),
        ({"queue_len": True}, "queue_len must be an integer"),
        ({"episode_mode": "endless"}, "episode_mode must be one of drain, paper"),
        ({"reward": "makespan"}, "reward must be one of ttd, length, ttd_length, pair_cost"),
        ({"noise_var": -0.1}, "noise_var must be >= 0"),
        ({"noise_var": float("nan")}, "noise_var must be a finite number"),
        ({"noise_var": float("inf")}, "noise_var must be a finite number"),
        ({"noise_mean": float("inf")}, "noise_mean must be a finite number"),
        ({"noise_mean": -100.0}, "noise_mean must be >= 0"),
        ({"num_robots": 2, "robot_starts": ((0, 0),)}, "robot_starts must hold num_robots=2"),
        ({"num_robots": 1, "robot_starts": ((0, 0, 0),)}, "robot_starts"),
        ({"num_robots": 2, "robot_free_times": (0.0,)}, "robot_free_times must hold"),
        ({"num_robots": 2, "robot_free_times": (0.0, -1.0)}, "robot_free_times must hold"),
    ],
)
def test_sim_config_validation(kwargs: dict[str, object], match: str) -> None:
    """Each bad SimConfig value raises ConfigError naming the env key."""
    with pytest.raises(ConfigError, match=match):
        SimConfig(**kwargs)  # type: ignore[arg-type]


def test_sim_construction_errors() -> None:
    """Mismatched distance model, too many robots, unknown simulator keys and blocked starts are
    errors."""
    layout = open_grid(3, 3)
    with pytest.raises(ConfigError, match="different layout"):
        WarehouseSim(SimConfig(), layout, EuclideanDistance(open_grid(3, 3)), RandomTasks())
    with pytest.raises(ConfigError, match="num_robots=10 exceeds the 9 free cells"):
        WarehouseSim(SimConfig(), layout, EuclideanDistance(layout), RandomTasks())
    with pytest.raises(ConfigError, match=r"unknown key sim\.robots; valid keys: num_robots"):
        build_sim(SimSpec.of({"robots": 3}, "open", "direct", "random"))
    grid = np.zeros((4, 4), dtype=bool)
    grid[1, 1] = True
    blocked = Layout(grid)
    config = SimConfig(num_robots=1, num_tasks=3, robot_starts=((1, 1),))
    sim = WarehouseSim(config, blocked, EuclideanDistance(blocked), RandomTasks())
    with pytest.raises(LayoutError, match=r"start of robot 0 at \(x=1, y=1\) is on an obstacle"):
        sim.reset(0)


def test_navigator_is_a_deprecated_alias_of_distance_model(
    poc_sim: Callable[..., WarehouseSim],
) -> None:
    """``sim.navigator`` still returns the distance model, with one ``DeprecationWarning``."""
    sim = poc_sim()
    with pytest.warns(DeprecationWarning, match=r"use \.distance_model") as caught:
        model = sim.navigator
    assert model is sim.distance_model
    assert isinstance(model, EuclideanDistance)
    assert len(caught) == 1


def test_unreachable_tasks_rejected_at_reset() -> None:
    """With A*, a task in a region the robots cannot reach is a LayoutError at reset."""
    grid = np.array([[c == "@" for c in row] for row in ("..@...", "..@...")])
    layout = Layout(grid)
    config = SimConfig(num_robots=1, num_tasks=1, queue_len=1, robot_starts=((4, 0),))
    tasks = FixedTasks([(0, 0, 1, 1)])
    sim = WarehouseSim(config, layout, GridDistance(layout), tasks)
    with pytest.raises(LayoutError, match="different connected regions"):
        sim.reset(0)


# ----------------------------------------------------------------- seeding and dynamics


def test_same_seed_same_episode() -> None:
    """The same seed gives the same tasks, starts, noise and metrics; other seeds differ."""

    def episode(seed: int) -> WarehouseSim:
        sim = small_sim()
        run(sim, RandomPolicy(), seed)
        return sim

    a, b, c = episode(9), episode(9), episode(10)
    assert np.array_equal(a.tasks, b.tasks)
    assert np.array_equal(a.robot_start_xy, b.robot_start_xy)
    assert np.array_equal(a.task_finished, b.task_finished)
    assert a.metrics() == b.metrics()
    assert not np.array_equal(a.tasks, c.tasks)
    assert not np.array_equal(a.robot_start_xy, c.robot_start_xy)
    assert a.metrics() != c.metrics()


def test_tasks_do_not_depend_on_policy() -> None:
    """For one seed every policy sees the same tasks and robot starts."""
    sims = []
    for policy in (MPDM(), RBTS(), RandomPolicy()):
        sim = small_sim()
        run(sim, policy, 3)
        sims.append(sim)
    for sim in sims[1:]:
        assert np.array_equal(sim.tasks, sims[0].tasks)
        assert np.array_equal(sim.robot_start_xy, sims[0].robot_start_xy)


def test_completion_noise_statistics() -> None:
    """Completion time = decision time + TTD + length + N(noise_mean, noise_var); zero variance
    adds exactly noise_mean."""
    sim = small_sim(num_tasks=600, num_robots=5, noise_mean=0.25, noise_var=0.25)
    run(sim, RandomPolicy(), 0)
    noise = sim.task_finished - sim.task_assigned - sim.task_ttd - sim.task_length
    assert abs(noise.mean() - 0.25) < 0.06
    assert abs(noise.std() - 0.5) < 0.06
    sim = small_sim(noise_mean=0.5, noise_var=0.0)
    run(sim, RandomPolicy(), 0)
    noise = sim.task_finished - sim.task_assigned - sim.task_ttd - sim.task_length
    np.testing.assert_allclose(noise, 0.5, atol=1e-9)


def test_zero_noise_ties_go_to_lowest_robot_id() -> None:
    """Robots free at the same time act in id order; each decision selects the lowest-id robot
    among those free earliest."""
    sim = small_sim(
        num_robots=4, noise_mean=0.0, noise_var=0.0, robot_free_times=(3.0, 1.0, 1.0, 2.0)
    )
    sim.reset(0)
    assert (sim.robot, sim.time) == (1, 1.0)
    sim = small_sim(num_robots=4, noise_mean=0.0, noise_var=0.0, num_tasks=60)
    sim.reset(2)
    policy = MPDM()
    policy.reset(2)
    first = []
    while not sim.done:
        earliest = np.flatnonzero(sim.robot_free_at == sim.robot_free_at.min())
        assert sim.robot == earliest[0]
        assert sim.time == sim.robot_free_at[sim.robot]
        first.append(sim.robot)
        sim.step(policy.act_sim(sim))
    assert first[:4] == [0, 1, 2, 3]


@pytest.mark.parametrize("seed", range(4))
def test_time_is_non_decreasing(seed: int) -> None:
    """Decision times never go backwards, even with large completion noise."""
    sim = small_sim(num_tasks=80, noise_mean=0.0, noise_var=9.0)
    sim.reset(seed)
    policy = RandomPolicy()
    policy.reset(seed)
    times = []
    while not sim.done:
        times.append(sim.time)
        assert (sim.robot_remaining() >= 0).all()
        sim.step(policy.act_sim(sim))
    assert (np.diff(times) >= 0).all()
    assert times[0] == 0.0


# ----------------------------------------------------------------- rewards and metrics


def test_rewards_match_metrics() -> None:
    """reward='ttd' sums to -TTD, 'length' to -task_length, 'ttd_length' to -(TTD + length),
    'pair_cost' to -(TTD + length / 5); the reward does not change the dynamics."""
    results = {}
    for reward in ("ttd", "length", "ttd_length", "pair_cost"):
        sim = small_sim(reward=reward)
        actions, rewards = run(sim, RandomPolicy(), 6)
        results[reward] = (actions, sum(rewards), sim.metrics())
    metrics = results["ttd"][2]
    assert results["length"][2] == metrics
    assert results["ttd_length"][2] == metrics
    assert results["length"][0] == results["ttd"][0]
    assert results["ttd"][1] == pytest.approx(-metrics.ttd, rel=1e-12)
    assert results["length"][1] == pytest.approx(-metrics.task_length, rel=1e-12)
    assert results["ttd_length"][1] == pytest.approx(-(metrics.ttd + metrics.task_length))
    assert results["pair_cost"][2] == metrics
    assert results["pair_cost"][1] == pytest.approx(-(metrics.ttd + metrics.task_length / 5))


def test_per_decision_reward_is_ttd(poc_sim: Callable[..., WarehouseSim]) -> None:
    """Each reward is minus the distance from the robot's cell to the chosen origin."""
    sim = poc_sim()
    sim.reset(0)
    xy = sim.robot_xy[sim.robot].copy()
    origin = sim.tasks[sim.queue_ids[1], :2]
    assert sim.step(1) == pytest.approx(-math.dist(xy, origin))
    assert sim.last_ttd == pytest.approx(math.dist(xy, origin))


@pytest.mark.parametrize("mode", ["drain", "paper"])
def test_metric_invariants(mode: str) -> None:
    """Waits >= 0, makespan >= every finish, idle >= 0 (zero noise), totals match records."""
    sim = small_sim(num_tasks=60, num_robots=4, episode_mode=mode, noise_mean=0.0, noise_var=0.0)
    run(sim, MPDM(), 8)
    metrics = sim.metrics()
    served = sim.task_robot >= 0
    wait = sim.task_assigned[served] + sim.task_ttd[served] - sim.task_arrival[served]
    assert (wait >= 0).all()
    assert metrics.wait_mean == pytest.approx(wait.mean())
    assert metrics.wait_max == pytest.approx(wait.max())
    assert metrics.makespan >= np.nanmax(sim.task_finished)
    assert metrics.makespan == pytest.approx(np.nanmax(sim.task_finished[served]))
    assert metrics.ttd == pytest.approx(sim.task_ttd[served].sum())
    assert metrics.task_length == pytest.approx(sim.task_length[served].sum())
    idle = sim.robot_idle()
    assert idle.shape == (4,)
    assert (idle >= -1e-9).all()
    assert metrics.idle_max == pytest.approx(idle.max())
    assert metrics.idle_mean == pytest.approx(idle.mean())
    assert (sim.task_arrival[served] <= sim.task_assigned[served]).all()
    assert set(metrics.as_dict()) >= {"ttd", "makespan", "idle_mean", "wait_max", "decisions"}


def test_metrics_before_any_decision() -> None:
    """Before the first decision the metrics are all zero."""
    sim = small_sim()
    sim.reset(0)
    metrics = sim.metrics()
    assert metrics.tasks_served == 0
    assert metrics.ttd == 0.0
    assert (sim.robot_idle() == 0).all()


def test_idle_is_non_negative_with_default_noise() -> None:
    """With the default noise (mean 0.25, var 0.25) idle time is still never negative."""
    sim = small_sim(num_robots=3, num_tasks=6, queue_len=3)
    for seed in range(20):
        run(sim, RandomPolicy(), seed)
        assert (sim.robot_idle() >= 0).all(), f"seed {seed}: idle {sim.robot_idle()}"
        assert sim.metrics().idle_max >= 0


# ----------------------------------------------------------------- scale


def test_scale_thousand_robots() -> None:
    """1000 robots and 2000 tasks on a 128x128 open grid with A* and MPDM: every task served
    exactly once and each TTD equals the Manhattan distance (smoke test, no timing)."""
    sim = build_sim(
        SimSpec.of(
            {"num_robots": 1000, "num_tasks": 2000},
            {"name": "open", "width": 128, "height": 128},
            "astar",
            "random",
        )
    )
    run(sim, MPDM(), 0)
    metrics = sim.metrics()
    assert sim.done
    assert metrics.tasks_served == 2000
    assert (sim.task_robot >= 0).all()
    assert len(np.unique(sim.robot_start_xy, axis=0)) == 1000
    lengths = np.abs(sim.tasks[:, :2] - sim.tasks[:, 2:]).sum(axis=1)
    np.testing.assert_array_equal(sim.task_length, lengths)
    assert metrics.ttd == pytest.approx(np.sum(sim.task_ttd))
    assert np.isfinite(metrics.makespan)
