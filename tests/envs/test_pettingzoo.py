"""Tests of the PettingZoo warehouse env ``warehouse_v1`` against its docstring spec.

Expected values come from independent oracles where possible: on an obstacle-free grid
the ``astar`` distance is the Manhattan distance and the ``direct`` distance the
Euclidean one, and noise-free dynamics can be replayed from the observations alone.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pettingzoo
import pytest
from pettingzoo.test import api_test, seed_test

import rtaw_marl
from rtaw_marl import warehouse_v1
from rtaw_marl.errors import ConfigError, InvalidActionError, LayoutError
from rtaw_marl.policies import MPDM, RBTS
from rtaw_marl.sim.mapf.conflicts import check_schedule

pytestmark = pytest.mark.unit

REPO_ROOT = Path(__file__).resolve().parents[2]
MAPS_DIR = REPO_ROOT.parent / "shared" / "maps"
USC_64 = MAPS_DIR / "rtaw" / "usc_64.cfg"

OPEN_64 = {"name": "open", "width": 64, "height": 64}

#: Warnings PettingZoo's checkers emit for any dict observation with a mask that may be
#: all zeros (non-selected agents) or of length 1 (queue_len=1), and the env's own for
#: ``api_test``'s dummy ``reset(options={"options": 1})``; nothing else may appear.
EXPECTED_API_WARNINGS = (
    "Observation is not a NumPy array",
    "Observation space for each agent probably should be",
    "Action mask numpy array is all zeros",
    "Action mask is a single number",
    "reset options ['options'] ignored: warehouse_v1's reset takes no options",
)


def unexpected_warnings(caught: list[warnings.WarningMessage]) -> list[str]:
    """The messages of ``caught`` outside :data:`EXPECTED_API_WARNINGS` (deprecations aside)."""
    return [
        str(w.message)
        for w in caught
        if not str(w.message).startswith(EXPECTED_API_WARNINGS)
        and not issubclass(w.category, DeprecationWarning)
    ]


#: The paper's proof of concept (appendix): 2 robots, 5 fixed tasks, queue of 2.
POC_KWARGS: dict[str, Any] = {
    "num_robots": 2,
    "num_tasks": 5,
    "queue_len": 2,
    "layout": {"name": "open", "width": 10, "height": 10},
    "navigator": "direct",
    "tasks": "poc",
    "noise_mean": 0,
    "noise_var": 0,
    "robot_starts": [[2, 2], [6, 2]],
    "robot_free_times": [0, 2],
}


# --------------------------------------------------------------------------- helpers
def first_valid(obs: dict[str, np.ndarray]) -> int:
    """The first legal slot of an observation."""
    return int(obs["action_mask"].argmax())


def is_done(env: Any) -> bool:
    """Whether the selected agent is terminated or truncated."""
    agent = env.agent_selection
    return bool(env.terminations[agent] or env.truncations[agent])


def copy_obs(obs: dict[str, Any]) -> dict[str, Any]:
    """A deep copy (``robots`` is shared between agents of one decision)."""
    return {
        key: copy_obs(value) if isinstance(value, dict) else value.copy()
        for key, value in obs.items()
    }


def assert_same_obs(a: dict[str, Any], b: dict[str, Any]) -> None:
    """Equal (nested) observations, array by array."""
    assert a.keys() == b.keys()
    for key in a:
        if isinstance(a[key], dict):
            assert_same_obs(a[key], b[key])
        else:
            np.testing.assert_array_equal(a[key], b[key])


def play(
    env: Any,
    choose: Callable[[dict[str, np.ndarray]], int] = first_valid,
    seed: int | None = None,
    reset: bool = True,
) -> Iterator[tuple[str, dict[str, np.ndarray], float, bool, bool, dict]]:
    """Run one full episode (dead steps included), yielding ``(agent, *last())`` per turn."""
    if reset:
        env.reset(seed=seed)
    for agent in env.agent_iter():
        obs, reward, terminated, truncated, info = env.last()
        yield agent, obs, reward, terminated, truncated, info
        env.step(None if terminated or truncated else choose(obs))


def trajectory(env: Any, seed: int | None, reset: bool = True) -> list[tuple[Any, ...]]:
    """``(agent, observation copy, reward, terminated, truncated)`` per turn of one episode."""
    return [
        (agent, copy_obs(obs), reward, term, trunc)
        for agent, obs, reward, term, trunc, _ in play(env, seed=seed, reset=reset)
    ]


def episode_return(
    env: Any, choose: Callable[[dict[str, np.ndarray]], int] = first_valid, seed: int | None = None
) -> tuple[float, dict]:
    """Sum of the rewards seen through ``last()`` over one episode, and the final info."""
    total = 0.0
    final: dict = {}
    for _, _, reward, terminated, truncated, info in play(env, choose=choose, seed=seed):
        total += reward
        if terminated or truncated:
            final = info
    return total, final


def assert_same_trajectory(a: list[tuple[Any, ...]], b: list[tuple[Any, ...]]) -> None:
    assert len(a) == len(b)
    for (agent_a, obs_a, *rest_a), (agent_b, obs_b, *rest_b) in zip(a, b, strict=True):
        assert agent_a == agent_b
        assert rest_a == rest_b
        assert_same_obs(obs_a, obs_b)


def oracle_distance(navigator: str, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Travel distance on an obstacle-free grid, computed without the package."""
    d = np.asarray(a, dtype=np.float64) - np.asarray(b, dtype=np.float64)
    if navigator == "astar":
        return np.abs(d).sum(axis=-1)
    return np.hypot(d[..., 0], d[..., 1])


# --------------------------------------------------------------------------- PettingZoo checks
@pytest.mark.parametrize(
    ("num_robots", "queue_len", "num_tasks", "layout", "mode"),
    [
        (1, 1, 30, "shelves", "drain"),
        (10, 10, 60, "shelves", "drain"),
        (10, 10, 60, "shelves", "paper"),
        (1000, 10, 40, OPEN_64, "drain"),
    ],
)
def test_pettingzoo_api_test(
    num_robots: int, queue_len: int, num_tasks: int, layout: Any, mode: str
) -> None:
    env = warehouse_v1.env(
        num_robots=num_robots,
        queue_len=queue_len,
        num_tasks=num_tasks,
        layout=layout,
        episode_mode=mode,
    )
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        api_test(env, num_cycles=num_tasks + 1)
    assert unexpected_warnings(caught) == []


@pytest.mark.parametrize("navigator", ["sipp", "cbs"])
def test_collision_aware_env_passes_api_test_and_reports_executed_ttd(navigator: str) -> None:
    """With SIPP/CBS the env is a normal AEC env; its episode TTD is the executed one."""
    kwargs = {"num_robots": 10, "num_tasks": 30, "noise_mean": 0.0, "noise_var": 0.0}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        api_test(warehouse_v1.env(navigator=navigator, **kwargs), num_cycles=31)
    env = warehouse_v1.env(navigator=navigator, **kwargs)
    env.reset(seed=1)
    for _ in env.agent_iter():
        obs, _, terminated, truncated, info = env.last()
        env.step(None if terminated or truncated else int(obs["action_mask"].argmax()))
    schedule = env.unwrapped.sim.schedule()
    check_schedule(env.unwrapped.sim.layout, schedule, expected_tasks=30)
    assert info["ttd"] == pytest.approx(float(schedule.task_ttd.sum()))
    assert len(schedule.tasks) == 30


@pytest.mark.parametrize(
    ("num_robots", "queue_len", "layout"),
    [(1, 1, "shelves"), (3, 2, "shelves"), (10, 10, "shelves"), (200, 5, OPEN_64)],
)
def test_pettingzoo_seed_test(num_robots: int, queue_len: int, layout: Any) -> None:
    seed_test(
        lambda: warehouse_v1.env(
            num_robots=num_robots, queue_len=queue_len, num_tasks=40, layout=layout
        ),
        num_cycles=50,
    )


def test_registry_make_and_metadata() -> None:
    assert rtaw_marl.ENV_ID == "rtaw/warehouse-v1"
    env = pettingzoo.make("aec", "rtaw/warehouse-v1", num_robots=3)
    assert isinstance(env.unwrapped, warehouse_v1.raw_env)
    assert env.metadata["name"] == "warehouse_v1"
    assert env.possible_agents == ["robot_0", "robot_1", "robot_2"]
    env.reset(seed=0)
    assert env.agents == env.possible_agents
    assert env.action_space("robot_0").n == 10


# --------------------------------------------------------------------------- episode length
@pytest.mark.parametrize(
    ("mode", "num_robots", "queue_len", "num_tasks"),
    [
        ("drain", 3, 4, 17),
        ("drain", 2, 6, 3),  # fewer tasks than slots: some slots are empty from the start
        ("drain", 1, 1, 5),
        ("paper", 3, 4, 17),
        ("paper", 1, 1, 5),
    ],
)
def test_episode_takes_exactly_num_tasks_decisions(
    mode: str, num_robots: int, queue_len: int, num_tasks: int
) -> None:
    env = warehouse_v1.env(
        num_robots=num_robots,
        queue_len=queue_len,
        num_tasks=num_tasks,
        episode_mode=mode,
        layout={"name": "open", "width": 12, "height": 9},
        tasks="random",
    )
    env.reset(seed=3)
    decisions = 0
    reward_sum = 0.0
    last_reward_sum = 0.0
    while not is_done(env):
        obs, reward, *_ = env.last()
        last_reward_sum += reward
        env.step(first_valid(obs))
        decisions += 1
        reward_sum += sum(env.rewards.values())
        assert decisions <= num_tasks
    assert decisions == num_tasks
    # Every agent is finished at once, in the mode's way.
    assert env.agents == env.possible_agents
    expect_term, expect_trunc = (mode == "drain"), (mode == "paper")
    assert all(v is expect_term for v in env.terminations.values())
    assert all(v is expect_trunc for v in env.truncations.values())

    dead_order = []
    while env.agents:
        agent = env.agent_selection
        obs, reward, terminated, truncated, info = env.last()
        assert (terminated, truncated) == (expect_term, expect_trunc)
        assert not obs["action_mask"].any()
        metrics = info
        assert metrics["decisions"] == num_tasks
        assert metrics["tasks_served"] == num_tasks
        assert metrics["ttd"] == pytest.approx(-reward_sum, rel=1e-9, abs=1e-9)
        last_reward_sum += reward
        env.step(None)
        dead_order.append(agent)
        assert agent not in env.agents
    # Each agent steps None exactly once; the last actor goes first, then in id order.
    assert sorted(dead_order) == sorted(env.possible_agents)
    assert dead_order[1:] == [a for a in env.possible_agents if a != dead_order[0]]
    assert env.agents == []
    # Rewards seen through last() add up to the same total as the per-step rewards.
    assert last_reward_sum == pytest.approx(reward_sum, rel=1e-9, abs=1e-9)


@pytest.mark.parametrize(
    ("reward", "expected"),
    [("ttd", ("ttd",)), ("length", ("task_length",)), ("ttd_length", ("ttd", "task_length"))],
)
def test_reward_variants_sum_to_metrics(reward: str, expected: tuple[str, ...]) -> None:
    env = warehouse_v1.env(num_robots=4, num_tasks=30, queue_len=5, reward=reward)
    total, info = episode_return(env, seed=11)
    metrics = info
    assert total < 0
    assert -total == pytest.approx(sum(metrics[k] for k in expected), rel=1e-9)


def test_reset_restarts_episode() -> None:
    env = warehouse_v1.env(num_robots=3, num_tasks=8, queue_len=3)
    first = trajectory(env, seed=4)
    again = trajectory(env, seed=4)  # after a finished episode
    assert_same_trajectory(first, again)
    env.reset(seed=4)
    obs, *_ = env.last()
    env.step(first_valid(obs))
    env.reset(seed=4)  # in the middle of an episode
    assert env.agents == env.possible_agents
    assert not any(env.terminations.values())
    assert not any(env.truncations.values())
    assert env.unwrapped.sim.decisions == 0
    np.testing.assert_array_equal(
        env.observe(first[0][0])["observation"]["tasks"], first[0][1]["observation"]["tasks"]
    )


# --------------------------------------------------------------------------- observations
def test_observation_shapes_dtypes_and_space() -> None:
    m, n = 6, 4
    env = warehouse_v1.env(num_robots=m, queue_len=n, num_tasks=20)
    env.reset(seed=0)
    space = env.observation_space("robot_0")
    keys = {"robots", "tasks", "agent", "relations", "rivals"}
    assert set(space.spaces) == {"observation", "action_mask"}
    assert set(space["observation"].spaces) == keys
    for agent in env.agents:
        obs = env.observe(agent)
        assert set(obs) == {"observation", "action_mask"}
        assert set(obs["observation"]) == keys
        assert obs["observation"]["relations"].shape == (n, 8)
        assert obs["observation"]["rivals"].shape == (n, 8, 4)
        assert (
            obs["observation"]["relations"].dtype
            == obs["observation"]["rivals"].dtype
            == np.float32
        )
        assert obs["observation"]["robots"].shape == (m, 3)
        assert obs["observation"]["robots"].dtype == np.float32
        assert obs["observation"]["tasks"].shape == (n, 6)
        assert obs["observation"]["tasks"].dtype == np.float32
        assert obs["observation"]["agent"].shape == (3,)
        assert obs["observation"]["agent"].dtype == np.float32
        assert obs["action_mask"].shape == (n,)
        assert obs["action_mask"].dtype == np.int8
        assert space.contains(obs)
        assert env.observation_space(agent) == space
        assert env.action_space(agent).n == n
    # The last observation of an episode is still inside the space.
    for _, obs, *_ in play(env, seed=1):
        assert space.contains(obs)


@pytest.mark.parametrize(("observation", "obs_format"), [("full", "dict"), ("compact", "flat")])
def test_observe_all_stacks_every_agents_observation(observation: str, obs_format: str) -> None:
    """Row ``i`` of ``observe_all()`` is ``observe(possible_agents[i])``, bit for bit, at
    every decision and at the episode's end (the acting row's mask included)."""
    env = warehouse_v1.env(
        num_robots=5, queue_len=4, num_tasks=12, observation=observation, obs_format=obs_format
    )
    env.reset(seed=3)
    checked = 0
    for agent in env.agent_iter():
        stacked = env.unwrapped.observe_all()
        for i, name in enumerate(env.possible_agents):
            one = env.observe(name)
            np.testing.assert_array_equal(stacked["action_mask"][i], one["action_mask"])
            if obs_format == "flat":
                np.testing.assert_array_equal(stacked["observation"][i], one["observation"])
            else:
                for key, value in one["observation"].items():
                    np.testing.assert_array_equal(stacked["observation"][key][i], value)
        checked += 1
        _, _, terminated, truncated, _ = env.last()
        mask = env.observe(agent)["action_mask"]
        env.step(None if terminated or truncated else int(np.flatnonzero(mask)[0]))
    assert checked == 12 + 5  # every decision, then every agent's final step


@pytest.mark.parametrize("navigator", ["astar", "direct"])
def test_observation_values_match_state_and_scale(navigator: str) -> None:
    """Every agent's observation at every decision, against an independent oracle."""
    width, height = 23, 14  # L = max(W, H) = 23
    env = warehouse_v1.env(
        num_robots=5,
        queue_len=4,
        num_tasks=25,
        layout={"name": "open", "width": width, "height": height},
        navigator=navigator,
        tasks="random",
    )
    raw = env.unwrapped
    assert raw.scale == 23.0
    env.reset(seed=7)
    sim = raw.sim
    checked = 0
    while not is_done(env):
        assert env.agent_selection == env.possible_agents[sim.robot]
        robots = np.column_stack(
            [sim.robot_xy, np.maximum(sim.robot_free_at - sim.time, 0.0)]
        ).astype(np.float64)
        queued = sim.queue_mask.copy()
        rows = np.where(queued[:, None], sim.tasks[np.maximum(sim.queue_ids, 0)], 0)
        length = np.where(queued, oracle_distance(navigator, rows[:, :2], rows[:, 2:]), 0.0)
        for i, agent in enumerate(env.agents):
            obs = env.observe(agent)
            np.testing.assert_allclose(
                obs["observation"]["robots"], robots / 23.0, rtol=1e-6, atol=1e-7
            )
            np.testing.assert_array_equal(
                obs["observation"]["agent"], obs["observation"]["robots"][i]
            )
            k = np.where(queued, oracle_distance(navigator, sim.robot_xy[i], rows[:, :2]), 0.0)
            expected = np.column_stack([rows, k, length]) / 23.0
            np.testing.assert_allclose(obs["observation"]["tasks"], expected, rtol=1e-6, atol=1e-7)
            if agent == env.agent_selection:
                np.testing.assert_array_equal(obs["action_mask"], queued.astype(np.int8))
                assert obs["observation"]["agent"][2] == 0.0
                # The selected robot is the lowest id among the robots free now.
                assert i == int(np.flatnonzero(obs["observation"]["robots"][:, 2] == 0.0)[0])
            else:
                assert not obs["action_mask"].any()
            checked += 1
        obs, *_ = env.last()
        env.step(first_valid(obs))
    assert checked == 25 * 5


def test_observation_dynamics_noise_free() -> None:
    """With noise off, the next observation follows from the previous one and the action."""
    env = warehouse_v1.env(
        num_robots=4,
        queue_len=5,
        num_tasks=40,
        noise_mean=0.0,
        noise_var=0.0,
        layout={"name": "open", "width": 20, "height": 20},
        navigator="astar",
        tasks="random",
    )
    scale = env.unwrapped.scale
    env.reset(seed=2)
    rng = np.random.default_rng(0)
    prev = None
    while not is_done(env):
        agent = env.agent_selection
        obs, *_ = env.last()
        robots = obs["observation"]["robots"].astype(np.float64) * scale
        if prev is not None:
            p_agent, p_robots, p_task = prev
            actor = env.possible_agents.index(p_agent)
            # The actor will next be free at its task's destination...
            np.testing.assert_allclose(robots[actor, :2], p_task[2:4], atol=1e-4)
            # ...after travelling k + l; everyone's clock advanced by the same amount.
            finish = p_robots.copy()
            finish[actor, 2] = p_task[4] + p_task[5]
            me = env.possible_agents.index(agent)
            elapsed = finish[me, 2]
            expected = np.maximum(finish[:, 2] - elapsed, 0.0)
            np.testing.assert_allclose(robots[:, 2], expected, atol=1e-3)
            others = np.arange(len(robots)) != actor
            np.testing.assert_allclose(robots[others, :2], p_robots[others, :2], atol=1e-4)
            # The actor's reward is minus the chosen task's k.
            assert env.rewards[p_agent] == pytest.approx(-p_task[4], abs=1e-3)
        slot = int(rng.choice(np.flatnonzero(obs["action_mask"])))
        prev = (agent, robots, obs["observation"]["tasks"][slot].astype(np.float64) * scale)
        env.step(slot)


def test_drain_end_has_empty_masked_slots() -> None:
    num_tasks, queue_len = 9, 4
    env = warehouse_v1.env(num_robots=2, queue_len=queue_len, num_tasks=num_tasks)
    env.reset(seed=5)
    decisions = 0
    saw_empty = False
    while not is_done(env):
        obs, *_ = env.last()
        empty = max(0, decisions - (num_tasks - queue_len))
        mask = obs["action_mask"].astype(bool)
        assert int(mask.sum()) == queue_len - empty
        # Empty slots are all-zero rows, and masked.
        np.testing.assert_array_equal(obs["observation"]["tasks"][~mask], 0.0)
        assert (obs["observation"]["tasks"][mask, 5] > 0).all()
        saw_empty |= empty > 0
        # Choose the last valid slot so empty slots appear in the middle too.
        env.step(int(np.flatnonzero(mask)[-1]))
        decisions += 1
    assert saw_empty
    for agent in env.agents:
        obs = env.observe(agent)
        np.testing.assert_array_equal(obs["observation"]["tasks"], 0.0)
        assert not obs["action_mask"].any()


def test_turn_order_ties_go_to_lowest_id() -> None:
    env = warehouse_v1.env(num_robots=4, num_tasks=20, queue_len=3)
    env.reset(seed=0)
    order = []
    for _ in range(4):
        order.append(env.agent_selection)
        obs, *_ = env.last()
        env.step(first_valid(obs))
    # All robots are free at time 0: they act in id order first.
    assert order == ["robot_0", "robot_1", "robot_2", "robot_3"]

    env = warehouse_v1.env(
        num_robots=4, num_tasks=20, queue_len=3, robot_free_times=[3.0, 0.5, 2.0, 0.5]
    )
    env.reset(seed=0)
    obs, *_ = env.last()
    assert env.agent_selection == "robot_1"
    np.testing.assert_allclose(
        obs["observation"]["robots"][:, 2] * env.unwrapped.scale, [2.5, 0.0, 1.5, 0.0], atol=1e-5
    )
    env.step(first_valid(obs))
    assert env.agent_selection == "robot_3"


def test_same_seed_same_trajectory_and_seed_matters() -> None:
    make = lambda: warehouse_v1.env(num_robots=5, num_tasks=30, queue_len=4)  # noqa: E731
    a = trajectory(make(), seed=123)
    b = trajectory(make(), seed=123)
    assert_same_trajectory(a, b)
    c = trajectory(make(), seed=124)
    assert [r for _, _, r, *_ in a] != [r for _, _, r, *_ in c]


def test_unseeded_reset_after_seeded_reset_is_reproducible() -> None:
    make = lambda: warehouse_v1.env(num_robots=4, num_tasks=20, queue_len=3)  # noqa: E731
    env_a, env_b = make(), make()
    seeded_a = trajectory(env_a, seed=9)
    seeded_b = trajectory(env_b, seed=9)
    assert_same_trajectory(seeded_a, seeded_b)
    for _ in range(2):
        env_a.reset()
        env_b.reset()
        next_a = trajectory(env_a, seed=None, reset=False)
        next_b = trajectory(env_b, seed=None, reset=False)
        assert_same_trajectory(next_a, next_b)
        # A new episode, not a replay of the seeded one.
        assert [r for _, _, r, *_ in next_a] != [r for _, _, r, *_ in seeded_a]


def test_final_observation_k_is_from_current_cell_paper_mode() -> None:
    env = warehouse_v1.env(
        num_robots=2,
        num_tasks=3,
        queue_len=3,
        episode_mode="paper",
        layout={"name": "open", "width": 10, "height": 10},
        navigator="direct",
        tasks="random",
        noise_var=0.0,
    )
    env.reset(seed=1)
    while not is_done(env):
        obs, *_ = env.last()
        env.step(first_valid(obs))
    assert all(env.truncations.values())
    for agent in env.agents:
        obs = env.observe(agent)
        robot = obs["observation"]["agent"][:2].astype(np.float64) * 10
        origins = obs["observation"]["tasks"][:, :2].astype(np.float64) * 10
        expected = oracle_distance("direct", robot, origins) / 10
        np.testing.assert_allclose(
            obs["observation"]["tasks"][:, 4], expected, rtol=1e-5, err_msg=agent
        )


# --------------------------------------------------------------------------- errors
def _env_at_first_decision(**kwargs: Any) -> Any:
    env = warehouse_v1.env(**kwargs)
    env.reset(seed=0)
    return env


@pytest.mark.parametrize("action", [4, 5, -1, 100, 1.5, "1"])
def test_out_of_range_actions_raise(action: Any) -> None:
    env = _env_at_first_decision(num_robots=2, num_tasks=10, queue_len=4)
    agent = env.agent_selection
    with pytest.raises(InvalidActionError):
        env.step(action)
    # Nothing happened; a legal action still works.
    assert env.agent_selection == agent
    assert env.unwrapped.sim.decisions == 0
    env.step(0)
    assert env.unwrapped.sim.decisions == 1


def test_masked_slot_raises() -> None:
    env = _env_at_first_decision(num_robots=2, num_tasks=2, queue_len=4)
    obs, *_ = env.last()
    np.testing.assert_array_equal(obs["action_mask"], [1, 1, 0, 0])
    for slot in (2, 3, np.int64(3)):
        with pytest.raises(InvalidActionError, match="empty"):
            env.step(slot)
    env.step(np.int32(1))
    obs, *_ = env.last()
    np.testing.assert_array_equal(obs["action_mask"], [1, 0, 0, 0])
    with pytest.raises(InvalidActionError, match="empty"):
        env.step(1)


def test_none_action_for_live_agent_and_action_for_dead_agent_raise() -> None:
    env = _env_at_first_decision(num_robots=2, num_tasks=1, queue_len=2)
    with pytest.raises(InvalidActionError, match=r"robot_0 is not done.*got None"):
        env.step(None)
    env.step(0)
    assert is_done(env)
    with pytest.raises(InvalidActionError, match="only valid action is None, got 0"):
        env.step(0)
    env.step(None)
    assert len(env.agents) == 1


#: Both ways to build the env: the wrapped ``env()`` and the bare ``raw_env``.
FACTORIES = pytest.mark.parametrize("make", [warehouse_v1.env, warehouse_v1.raw_env])

#: Actions that are not an integer scalar, each with the words its error must contain.
NOT_INTEGER_ACTIONS = [
    (float("inf"), ["integer slot index", "inf", "float"]),
    (float("nan"), ["integer slot index", "nan"]),
    (1.0, ["integer slot index", "1.0", "float"]),
    (-0.0, ["integer slot index"]),
    (np.float32(1), ["integer slot index", "float32"]),
    (np.array(1.0), ["integer slot index"]),
    (True, ["integer slot index", "True", "bool"]),
    (False, ["integer slot index", "bool"]),
    (np.bool_(True), ["integer slot index", "bool"]),
    ("1", ["integer slot index", "'1'", "str"]),
    (np.array([1]), ["integer slot index", "shape (1,)"]),
    (np.array([[0, 1]]), ["integer slot index", "shape (1, 2)"]),
    (None, ["robot_0 is not done", "0..3", "None"]),
]


@FACTORIES
@pytest.mark.parametrize(("action", "words"), NOT_INTEGER_ACTIONS, ids=repr)
def test_non_integer_actions_raise_and_change_nothing(
    make: Callable[..., Any], action: Any, words: list[str]
) -> None:
    env = make(num_robots=2, num_tasks=10, queue_len=4)
    env.reset(seed=0)
    agent = env.agent_selection
    with pytest.raises(InvalidActionError) as excinfo:
        env.step(action)
    message = str(excinfo.value)
    for word in words:
        assert word in message, f"{word!r} not in {message!r}"
    assert env.agent_selection == agent
    assert env.unwrapped.sim.decisions == 0
    assert not env.terminations[agent]
    assert env.rewards[agent] == 0.0
    env.step(1)
    assert env.unwrapped.sim.decisions == 1


@FACTORIES
@pytest.mark.parametrize(
    "action", [1, np.int64(1), np.int32(1), np.uint8(1), np.array(1)], ids=repr
)
def test_integer_actions_of_any_integer_type_work(make: Callable[..., Any], action: Any) -> None:
    """NumPy integers and 0-d integer arrays name the same slot as the Python int."""
    env = make(num_robots=2, num_tasks=10, queue_len=4)
    env.reset(seed=0)
    reference = make(num_robots=2, num_tasks=10, queue_len=4)
    reference.reset(seed=0)
    agent = env.agent_selection
    env.step(action)
    reference.step(1)
    assert env.unwrapped.sim.decisions == 1
    assert env.rewards[agent] == reference.rewards[agent]
    assert env.agent_selection == reference.agent_selection


@FACTORIES
@pytest.mark.parametrize(
    "seed", [-1, 1.5, "a", True, np.float64(2.0), np.int64(-3), [1], np.array([1])], ids=repr
)
def test_bad_seeds_raise_config_errors(make: Callable[..., Any], seed: Any) -> None:
    env = make(num_robots=2, num_tasks=10, queue_len=4)
    with pytest.raises(ConfigError, match=r"seed must be an integer >= 0, got "):
        env.reset(seed=seed)
    env.reset(seed=0)  # the env is still usable
    assert env.agents == ["robot_0", "robot_1"]


@FACTORIES
def test_good_seeds_none_and_any_non_negative_integer(make: Callable[..., Any]) -> None:
    env = make(num_robots=2, num_tasks=6, queue_len=3)
    reference = trajectory(env, seed=7)
    for seed in (np.int64(7), np.uint32(7), np.array(7)):
        assert_same_trajectory(trajectory(env, seed=seed), reference)
    for seed in (None, 0, 2**70):
        env.reset(seed=seed)
        assert env.agents == ["robot_0", "robot_1"]


@FACTORIES
@pytest.mark.parametrize("mode", ["drain", "paper"])
def test_last_after_every_agent_is_done(make: Callable[..., Any], mode: str) -> None:
    """Once every agent has been removed, last() answers for agent_selection (the last
    agent removed): final observation, reward 0, the episode's flags and its info."""
    env = make(num_robots=3, num_tasks=4, queue_len=2, episode_mode=mode)
    finals = [turn for turn in play(env, seed=1) if turn[3] or turn[4]]
    assert env.agents == []
    assert env.rewards == env.terminations == env.truncations == env.infos == {}
    assert sorted(turn[0] for turn in finals) == ["robot_0", "robot_1", "robot_2"]
    obs, reward, terminated, truncated, info = env.last()
    assert env.agent_selection == finals[-1][0]
    assert reward == 0.0
    assert (terminated, truncated) == ((True, False) if mode == "drain" else (False, True))
    assert info == finals[-1][5]
    assert info["decisions"] == 4
    assert env.observation_space(env.agent_selection).contains(obs)
    assert not obs["action_mask"].any()
    assert env.last(observe=False)[0] is None
    if make is warehouse_v1.raw_env:
        with pytest.raises(InvalidActionError, match="call reset"):
            env.step(None)
    env.reset(seed=1)  # a new episode starts as usual
    assert env.last()[1:3] == (0.0, False)


@pytest.mark.parametrize(
    ("kwargs", "error", "words"),
    [
        ({"num_robots": 0}, ConfigError, ["num_robots", ">= 1", "0"]),
        ({"queue_len": 0}, ConfigError, ["queue_len", ">= 1"]),
        ({"num_tasks": 0}, ConfigError, ["num_tasks"]),
        ({"num_robots": 2.5}, ConfigError, ["num_robots", "integer"]),
        ({"episode_mode": "forever"}, ConfigError, ["episode_mode", "forever", "drain"]),
        ({"reward": "profit"}, ConfigError, ["reward", "profit", "ttd"]),
        ({"noise_var": -1.0}, ConfigError, ["noise_var"]),
        ({"navigator": "dijkstra"}, ConfigError, ["navigator", "'dijkstra'", "astar", "direct"]),
        ({"layout": "maze"}, ConfigError, ["layout", "'maze'", "open", "shelves"]),
        ({"layout": {"name": "mazes"}}, ConfigError, ["layout", "'mazes'"]),
        ({"layout": {"name": "open", "depth": 3}}, ConfigError, ["depth", "width"]),
        ({"tasks": "teleport"}, ConfigError, ["tasks", "'teleport'", "designated"]),
        ({"tasks": {"name": "random", "rate": 2}}, ConfigError, ["rate"]),
        ({"layout": "/nonexistent/dir/missing.cfg"}, LayoutError, ["not found", "missing.cfg"]),
        (
            {"num_robots": 30, "layout": {"name": "open", "width": 5, "height": 5}},
            ConfigError,
            ["num_robots=30", "25 free cells"],
        ),
        ({"num_robots": 2, "robot_starts": [[0, 0]]}, ConfigError, ["robot_starts"]),
        ({"num_robots": 2, "robot_free_times": [0.0, -1.0]}, ConfigError, ["robot_free_times"]),
        ({"render_mode": "rgb_array"}, ConfigError, ["render_mode", "rgb_array", "ansi"]),
        ({"observation": "local"}, ConfigError, ["observation", "'local'", "full", "compact"]),
        ({"obs_format": "box"}, ConfigError, ["obs_format", "'box'", "dict", "flat"]),
    ],
)
def test_bad_kwargs_raise_config_errors(
    kwargs: dict[str, Any], error: type[Exception], words: list[str]
) -> None:
    with pytest.raises(error) as excinfo:
        warehouse_v1.env(**kwargs)
    message = str(excinfo.value)
    for word in words:
        assert word in message, f"{word!r} not in {message!r}"


def test_layout_file_errors_are_config_errors(tmp_path: Path) -> None:
    assert issubclass(LayoutError, ConfigError)
    bad = tmp_path / "bad.cfg"
    bad.write_text("not a layout\n")
    with pytest.raises(ConfigError, match="environment:"):
        warehouse_v1.env(layout=str(bad))
    blocked = tmp_path / "tiny.txt"
    blocked.write_text("..@\n...\n")
    env = warehouse_v1.env(
        layout=str(blocked), num_robots=1, robot_starts=[[2, 0]], tasks="random", num_tasks=3
    )
    with pytest.raises(LayoutError, match="obstacle"):
        env.reset(seed=0)


# --------------------------------------------------------------------------- rendering
def test_render_ansi_poc_layout() -> None:
    env = warehouse_v1.env(render_mode="ansi", **POC_KWARGS)
    env.reset(seed=0)
    text = env.render()
    assert isinstance(text, str)
    lines = text.split("\n")
    assert len(lines) == 10 + 1
    grid = lines[:10]
    assert all(len(row) == 10 for row in grid)
    # Robot 0 (free at t=0) chooses now at (2, 2); robot 1 waits at (6, 2).
    assert grid[2][2] == "*"
    assert grid[2][6] == "R"
    # Queued: (2, 9) -> (5, 5) and (4, 4) -> (0, 0); rows are y, columns x.
    assert grid[9][2] == "o"
    assert grid[4][4] == "o"
    assert grid[5][5] == "d"
    assert grid[0][0] == "d"
    assert sum(row.count(".") for row in grid) == 100 - 6
    status = lines[10]
    for part in ("t=0.00", "decision 0/5", "robot 0", "queued 2/2"):
        assert part in status


def test_render_ansi_characters_and_obstacles() -> None:
    env = warehouse_v1.env(render_mode="ansi", num_robots=6, num_tasks=12, queue_len=4)
    raw = env.unwrapped
    height, width = raw.sim.layout.obstacles.shape
    for _, _, _, terminated, truncated, _ in play(env, seed=3):
        lines = env.render().split("\n")
        assert len(lines) == height + 1
        grid = np.array([list(row) for row in lines[:height]])
        assert grid.shape == (height, width)
        assert set(np.unique(grid)) <= set(".@doR*")
        np.testing.assert_array_equal(grid == "@", raw.sim.layout.obstacles)
        assert (grid == "*").sum() == (0 if terminated or truncated else 1)
        assert lines[-1].startswith("t=")


def test_render_none_returns_none() -> None:
    env = warehouse_v1.env(num_robots=2, num_tasks=5)
    env.reset(seed=0)
    assert env.render() is None


def test_navigator_property_is_a_deprecated_alias_of_distance_model() -> None:
    """``env.navigator`` (raw or wrapped) still returns the simulator's distance model, with
    one ``DeprecationWarning``; ``env.distance_model`` warns about nothing."""
    env = warehouse_v1.env(num_robots=2, num_tasks=3, navigator="direct")
    raw = env.unwrapped
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        model = raw.distance_model
    assert model is raw.sim.distance_model
    for source in (raw, env):
        with pytest.warns(DeprecationWarning, match=r"use \.distance_model") as caught:
            assert source.navigator is model
        assert len(caught) == 1


# --------------------------------------------------------------------------- paper numbers
def _poc_total(policy_name: str, seed: int) -> float:
    env = warehouse_v1.env(**POC_KWARGS)
    raw = env.unwrapped
    if policy_name == "mpdm":
        policy = MPDM(scale=raw.scale)
    else:
        policy = RBTS(distance_model=raw.distance_model, scale=raw.scale)
    policy.reset(seed)
    total, info = episode_return(env, choose=policy.act, seed=seed)
    assert info["ttd"] == pytest.approx(-total, rel=1e-12)
    assert info["tasks_served"] == 5
    return -total


@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize(("policy_name", "ttd"), [("mpdm", 22.737), ("rbts", 18.463)])
def test_paper_proof_of_concept_ttd(policy_name: str, ttd: float, seed: int) -> None:
    assert _poc_total(policy_name, seed) == pytest.approx(ttd, abs=0.01)


@pytest.mark.skipif(not USC_64.is_file(), reason=f"shared map {USC_64} not present")
def test_usc_map_episode_with_mpdm() -> None:
    env = warehouse_v1.env(num_robots=20, num_tasks=60, queue_len=10, layout=str(USC_64))
    raw = env.unwrapped
    assert raw.scale == 64.0
    space = env.observation_space("robot_0")
    policy = MPDM(scale=raw.scale)
    policy.reset(0)

    def act(obs: dict[str, np.ndarray]) -> int:
        assert space.contains(obs)
        return policy.act(obs)

    total, info = episode_return(env, choose=act, seed=0)
    assert info["tasks_served"] == 60
    assert info["ttd"] == pytest.approx(-total, rel=1e-9)
