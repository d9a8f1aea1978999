"""Baseline policies: MPDM, RBTS and random, on the simulator and on env observations."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

from rtaw_marl import warehouse_v1
from rtaw_marl.errors import ConfigError
from rtaw_marl.policies import (
    BASELINES,
    MPDM,
    RBTS,
    BaselinePolicy,
    RandomPolicy,
    make_baseline,
)
from rtaw_marl.sim.builder import SimSpec, build_sim
from rtaw_marl.sim.config import SimConfig
from rtaw_marl.sim.core import WarehouseSim
from rtaw_marl.sim.distances import EuclideanDistance
from rtaw_marl.sim.layout import open_grid
from rtaw_marl.sim.tasks import FixedTasks

pytestmark = pytest.mark.unit

#: The two observation-path settings: (navigator, layout spec).
SETTINGS: dict[str, tuple[str, dict[str, Any]]] = {
    "direct-open": ("direct", {"name": "open", "width": 20, "height": 20}),
    "astar-shelves": ("astar", {"name": "shelves", "width": 30, "height": 24}),
}


def run_sim(sim: WarehouseSim, policy: BaselinePolicy, seed: int) -> tuple[list[int], float]:
    """Play one episode on the bare simulator; the chosen slots and the total TTD."""
    sim.reset(seed)
    policy.reset(seed)
    actions: list[int] = []
    total = 0.0
    while not sim.done:
        action = policy.act_sim(sim)
        actions.append(action)
        total -= sim.step(action)
    return actions, total


def two_task_sim(num_tasks: int = 500) -> WarehouseSim:
    """The paper's two-task setting: 10 robots, 10x10 open grid, direct, paper mode."""
    return build_sim(
        SimSpec.of(
            {"num_robots": 10, "num_tasks": num_tasks, "queue_len": 2, "episode_mode": "paper"},
            {"name": "open", "width": 10, "height": 10},
            "direct",
            "two_task",
        )
    )


def random_sim(navigator: str, layout: dict[str, Any], **sim: Any) -> WarehouseSim:
    values: dict[str, Any] = {"num_robots": 4, "num_tasks": 60, "queue_len": 5}
    values.update(sim)
    return build_sim(SimSpec.of(values, layout, navigator, "random"))


# ----------------------------------------------------------------- MPDM


@pytest.mark.parametrize("setting", sorted(SETTINGS))
def test_mpdm_picks_nearest(setting: str) -> None:
    """At every decision MPDM's slot has the smallest navigator distance among valid slots."""
    nav_name, layout = SETTINGS[setting]
    sim = random_sim(nav_name, layout)
    sim.reset(0)
    policy = MPDM()
    policy.reset(0)
    while not sim.done:
        slot = policy.act_sim(sim)
        valid = np.flatnonzero(sim.queue_mask)
        origins = sim.tasks[sim.queue_ids[valid], :2]
        here = np.repeat(sim.robot_xy[sim.robot][None], len(valid), axis=0)
        d = sim.distance_model.distance(here, origins)
        assert slot in valid
        assert d[valid.tolist().index(slot)] == pytest.approx(d.min())
        sim.step(slot)


@pytest.mark.parametrize("setting", sorted(SETTINGS))
def test_lorr_default_picks_least_pickup_plus_delivery_travel(setting: str) -> None:
    """At every decision the kit's greedy takes a task of least distance to its origin
    plus its length, and that is not always MPDM's nearest origin."""
    nav_name, layout = SETTINGS[setting]
    sim = random_sim(nav_name, layout)
    sim.reset(0)
    policy = make_baseline("lorr_default")
    differs = 0
    while not sim.done:
        slot = policy.act_sim(sim)
        valid = np.flatnonzero(sim.queue_mask)
        travel = sim.robot_distances()[valid] + sim.queue_length[valid]
        assert slot in valid
        assert travel[valid.tolist().index(slot)] == pytest.approx(travel.min())
        d = sim.robot_distances()[valid]
        differs += d[valid.tolist().index(slot)] > d.min() + 1e-9
        sim.step(slot)
    assert differs > 0


def test_mpdm_ties_random_but_reproducible() -> None:
    """In the two-task setting both pickups are equally close: MPDM picks each of them over 500
    decisions, the same way for the same reset seed and differently for another seed."""
    sim = two_task_sim()
    a, ttd_a = run_sim(sim, MPDM(), 1)
    b, ttd_b = run_sim(sim, MPDM(), 1)
    c, _ = run_sim(sim, MPDM(), 2)
    assert len(a) == 500
    assert a == b
    assert ttd_a == ttd_b
    assert a != c
    assert {0, 1} == set(a)
    assert 150 < a.count(0) < 350


# ----------------------------------------------------------------- RBTS


def _three_robot_sim(
    starts: tuple[tuple[int, int], ...], tasks: list[tuple[int, int, int, int]]
) -> WarehouseSim:
    """Three robots on a 10x10 open grid, direct, zero noise; robot 0 free first."""
    layout = open_grid(10, 10)
    config = SimConfig(
        num_robots=3,
        num_tasks=len(tasks),
        queue_len=len(tasks),
        noise_mean=0.0,
        noise_var=0.0,
        robot_starts=starts,
        robot_free_times=(0.0, 1.0, 1.0),
    )
    return WarehouseSim(config, layout, EuclideanDistance(layout), FixedTasks(tasks))


HAND_STARTS = ((0, 0), (2, 0), (9, 9))
HAND_TASKS = [(1, 0, 5, 5), (0, 4, 5, 5), (0, 7, 5, 5)]


def test_rbts_regret_by_hand() -> None:
    """Hand-computed regrets for robot 0 at (0,0), others at (2,0) and (9,9):
    task (1,0): min(1, hypot(8,9)) - 1 = 0; task (0,4): hypot(2,4) - 4 = 0.472;
    task (0,7): hypot(2,7) - 7 = 0.280. RBTS takes (0,4); MPDM takes the nearest, (1,0)."""
    regrets = [
        min(1.0, math.hypot(8, 9)) - 1.0,
        min(math.hypot(2, 4), math.hypot(9, 5)) - 4.0,
        min(math.hypot(2, 7), math.hypot(9, 2)) - 7.0,
    ]
    assert regrets == pytest.approx([0.0, 0.4721, 0.2801], abs=1e-4)
    sim = _three_robot_sim(HAND_STARTS, HAND_TASKS)
    sim.reset(0)
    assert sim.robot == 0
    rbts = RBTS()
    rbts.reset(0)
    assert rbts.act_sim(sim) == 1
    mpdm = MPDM()
    mpdm.reset(0)
    assert mpdm.act_sim(sim) == 0
    # The env's observation path agrees (RBTS needs the distance model there).
    env = warehouse_v1.env(
        num_robots=3,
        num_tasks=3,
        queue_len=3,
        noise_mean=0.0,
        noise_var=0.0,
        robot_starts=HAND_STARTS,
        robot_free_times=[0.0, 1.0, 1.0],
        layout=open_grid(10, 10),
        navigator="direct",
        tasks=FixedTasks(HAND_TASKS),
    )
    env.reset(seed=0)
    obs = env.observe(env.agent_selection)
    raw = env.unwrapped
    assert RBTS(distance_model=raw.distance_model, scale=raw.scale).act(obs) == 1


def test_rbts_counts_busy_robots_at_their_destination() -> None:
    """Other robots count at the cell where they will next be free. Robot 0 takes (0,1)->(7,0);
    then robot 1 at (4,0) chooses between (8,0) and (0,3). With robot 0 at (7,0) the regrets are
    1 - 4 = -3 and hypot(7,3) - 5 = 2.6, so RBTS takes (0,3); had robot 0 stayed at (0,0) it
    would take (8,0) (regrets 4 and -2). MPDM takes (8,0)."""
    sim = _three_robot_sim(((0, 0), (4, 0), (9, 9)), [(0, 1, 7, 0), (8, 0, 5, 5), (0, 3, 5, 5)])
    sim.reset(0)
    policy = RBTS()
    policy.reset(0)
    assert policy.act_sim(sim) == 0
    sim.step(0)
    assert sim.robot == 1
    assert sim.queue_mask.tolist() == [False, True, True]
    me, targets = (4, 0), {1: (8, 0), 2: (0, 3)}

    def best(others: list[tuple[int, int]]) -> int:
        regret = {
            s: min(math.dist(o, xy) for o in others) - math.dist(me, xy)
            for s, xy in targets.items()
        }
        return max(regret, key=regret.__getitem__)

    assert best([(7, 0), (9, 9)]) == 2
    assert best([(0, 0), (9, 9)]) == 1
    assert policy.act_sim(sim) == 2
    mpdm = MPDM()
    mpdm.reset(0)
    assert mpdm.act_sim(sim) == 1


@pytest.mark.parametrize("setting", sorted(SETTINGS))
def test_rbts_single_robot_equals_mpdm(setting: str) -> None:
    """With one robot there is no other robot: RBTS makes MPDM's choices (ties included)."""
    nav_name, layout = SETTINGS[setting]
    sim = random_sim(nav_name, layout, num_robots=1)
    for seed in (0, 1):
        assert run_sim(sim, RBTS(), seed) == run_sim(sim, MPDM(), seed)


# ----------------------------------------------------------------- random


def test_random_policy_valid_and_seeded() -> None:
    """Random picks only valid slots (also as the queue drains), every slot eventually, and is
    reproducible for the same seed."""
    sim = random_sim("direct", SETTINGS["direct-open"][1], num_tasks=200)
    sim.reset(0)
    policy = RandomPolicy()
    policy.reset(0)
    picks = []
    while not sim.done:
        slot = policy.act_sim(sim)
        assert sim.queue_mask[slot]
        picks.append(slot)
        sim.step(slot)
    assert set(picks) == set(range(5))
    again = run_sim(sim, RandomPolicy(), 0)[0]
    assert again == picks
    assert run_sim(sim, RandomPolicy(), 1)[0] != picks


def test_random_policy_respects_mask_on_observations() -> None:
    """On observations, the random policy only picks slots with action_mask 1."""
    policy = RandomPolicy()
    policy.reset(3)
    mask = np.array([0, 1, 0, 1, 0], dtype=np.int8)
    picks = {policy.act({"action_mask": mask}) for _ in range(50)}
    assert picks == {1, 3}


# ----------------------------------------------------------------- observation path


def _run_env(
    policy: BaselinePolicy,
    seed: int,
    nav_name: str,
    layout: dict[str, Any],
    num_robots: int,
    **env_keys: Any,
) -> tuple[list[int], float, float]:
    """Play one episode through the PettingZoo env with policy.act(obs)."""
    env = warehouse_v1.env(
        num_robots=num_robots,
        num_tasks=60,
        queue_len=5,
        layout=layout,
        navigator=nav_name,
        tasks="random",
        **env_keys,
    )
    env.reset(seed=seed)
    raw = env.unwrapped
    policy.bind(raw)
    policy.reset(seed)
    actions: list[int] = []
    reward_sum = 0.0
    episode_ttd = math.nan
    for agent in env.agent_iter():
        obs, reward, terminated, truncated, info = env.last()
        reward_sum += reward
        if terminated or truncated:
            episode_ttd = info["ttd"]
            env.step(None)
            continue
        action = policy.act(obs)
        assert obs["action_mask"][action] == 1
        assert agent == f"robot_{raw.sim.robot}"
        actions.append(action)
        env.step(action)
    return actions, -reward_sum, episode_ttd


@pytest.mark.parametrize("num_robots", [1, 5])
@pytest.mark.parametrize("setting", sorted(SETTINGS))
@pytest.mark.parametrize("name", ["mpdm", "rbts", "lorr_default", "random"])
def test_observation_path_matches_simulator(name: str, setting: str, num_robots: int) -> None:
    """policy.act on env observations chooses exactly the actions of act_sim on a bare
    simulator with the same seed and config, and gives the same total TTD."""
    nav_name, layout = SETTINGS[setting]
    seed = 17
    sim = random_sim(nav_name, layout, num_robots=num_robots)
    expected, expected_ttd = run_sim(sim, make_baseline(name), seed)
    env_policy = make_baseline(name)
    actions, reward_ttd, episode_ttd = _run_env(env_policy, seed, nav_name, layout, num_robots)
    assert actions == expected
    assert reward_ttd == pytest.approx(expected_ttd, rel=1e-9)
    assert episode_ttd == pytest.approx(expected_ttd, rel=1e-9)


def test_rbts_observation_path_needs_a_distance_model() -> None:
    """RBTS.act without a distance model is a ConfigError (it must measure other robots)."""
    obs = {
        "robots": np.zeros((2, 3), np.float32),
        "tasks": np.zeros((2, 6), np.float32),
        "agent": np.zeros(3, np.float32),
        "action_mask": np.ones(2, np.int8),
    }
    with pytest.raises(ConfigError, match="distance model"):
        RBTS().act(obs)


def test_navigator_keyword_is_a_deprecated_name_of_distance_model() -> None:
    """``RBTS(navigator=...)`` (the documented spelling before ``distance_model``) still
    binds the distance model, with one ``DeprecationWarning``; giving both is an error."""
    layout = open_grid(4, 4)
    model = EuclideanDistance(layout)
    deprecated = r"RBTS\(navigator=\.\.\.\) is deprecated, use distance_model="
    with pytest.warns(DeprecationWarning, match=deprecated) as caught:
        rbts = RBTS(navigator=model, scale=4.0)
    assert len(caught) == 1
    assert rbts.distance_model is model
    assert rbts.scale == 4.0
    with pytest.raises(TypeError, match="both distance_model and navigator"):
        RBTS(model, navigator=model)


# ----------------------------------------------------------------- registry


def test_make_baseline() -> None:
    """make_baseline builds each registered rule, bound to an env's distance model, scale and
    noise when given one (a simulator or an env); the rest is keyword-only; an unknown
    name lists mpdm, random and rbts."""
    assert {"mpdm", "rbts", "random"} <= set(BASELINES)
    env = warehouse_v1.env(num_robots=3, num_tasks=5, layout=open_grid(4, 4), navigator="direct")
    sim = env.unwrapped.sim
    for name, cls in (("mpdm", MPDM), ("rbts", RBTS), ("random", RandomPolicy)):
        assert type(make_baseline(name)) is cls
        for source in (env, sim):
            policy = make_baseline(name, env=source)
            assert type(policy) is cls
            assert policy.distance_model is sim.distance_model
            assert policy.scale == 4.0
            assert policy.noise_mean == sim.config.noise_mean
    with pytest.raises(TypeError):
        make_baseline("mpdm", sim)  # type: ignore[misc]
    with pytest.raises(TypeError, match="expected a WarehouseSim"):
        make_baseline("mpdm", env=object())
    with pytest.raises(ConfigError, match="unknown policy 'greedy'; available: batch, hindsi"):
        make_baseline("greedy")
