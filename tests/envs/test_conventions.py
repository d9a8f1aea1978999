"""PettingZoo conventions of ``warehouse_v1`` over every observation option.

PettingZoo's own checks (``api_test``, ``seed_test``, ``render_test``,
``performance_benchmark``, the state checks) on both ``observation`` options and both
``obs_format`` values, plus what they do not check: the observations lie in the declared
spaces (values, not only types), the flat vector is the dict, the state and the infos
hold what the docstring says, ``np_random`` is seeded.
"""

from __future__ import annotations

import dataclasses
import importlib
import warnings
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest
from gymnasium.utils import seeding
from pettingzoo.test import api_test, performance_benchmark, render_test, seed_test

from rtaw_marl import warehouse_v1
from rtaw_marl.decision.features import nearest_other, relational_features
from rtaw_marl.decision.observations import FEATURE_KEYS
from rtaw_marl.envs.pettingzoo import zero_info
from rtaw_marl.sim.metrics import EpisodeMetrics
from tests.envs.test_pettingzoo import first_valid, is_done, play, unexpected_warnings

pytestmark = pytest.mark.unit

# pettingzoo.test re-exports functions under their modules' names: take the modules.
pz_state = importlib.import_module("pettingzoo.test.state_test")
pz_benchmark = importlib.import_module("pettingzoo.test.performance_benchmark")

SMALL: dict[str, Any] = {
    "num_robots": 3,
    "queue_len": 4,
    "num_tasks": 12,
    "layout": {"name": "open", "width": 12, "height": 9},
    "tasks": "random",
}
OPTIONS = [(obs, fmt) for obs in ("full", "compact") for fmt in ("dict", "flat")]
EACH_OPTION = pytest.mark.parametrize(("observation", "obs_format"), OPTIONS)

#: The state checker's warnings that apply: the state space is unbounded above on purpose.
EXPECTED_STATE_WARNINGS = ("Environment's maximum state space value is infinity",)


def make(observation: str = "full", obs_format: str = "dict", **kwargs: Any) -> Any:
    return warehouse_v1.env(observation=observation, obs_format=obs_format, **{**SMALL, **kwargs})


# --------------------------------------------------------------------------- PettingZoo's checks
@EACH_OPTION
@pytest.mark.parametrize("mode", ["drain", "paper"])
def test_api_test(observation: str, obs_format: str, mode: str) -> None:
    env = make(observation, obs_format, episode_mode=mode)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        api_test(env, num_cycles=SMALL["num_tasks"] + 1)
    assert unexpected_warnings(caught) == []


@EACH_OPTION
def test_seed_test(observation: str, obs_format: str) -> None:
    seed_test(lambda: make(observation, obs_format), num_cycles=20)


@EACH_OPTION
def test_render_test(observation: str, obs_format: str, capsys: pytest.CaptureFixture) -> None:
    render_test(lambda render_mode=None: make(observation, obs_format, render_mode=render_mode))
    grid = capsys.readouterr().out  # human mode printed the grid
    assert "decision" in grid
    assert grid.count("\n") >= 5 * (9 + 1)


@EACH_OPTION
def test_performance_benchmark(
    observation: str, obs_format: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    """PettingZoo's benchmark loop (random legal actions, resets after episode ends), with
    its 5-second clock sped up: 1 s per call, so it runs a few cycles."""
    clock = iter(range(10_000))
    monkeypatch.setattr(pz_benchmark, "time", SimpleNamespace(time=lambda: float(next(clock))))
    env = make(observation, obs_format, num_tasks=2)
    performance_benchmark(env)
    assert env.unwrapped.sim.decisions <= 2


@EACH_OPTION
def test_state_checks(observation: str, obs_format: str) -> None:
    # PettingZoo's state test samples actions without the mask: paper mode keeps every
    # slot full, so every sampled slot is legal.
    env = make(observation, obs_format, episode_mode="paper")
    env.reset(seed=0)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        pz_state.test_state_space(env)
        pz_state.test_state(env, num_cycles=10)
    messages = [str(w.message) for w in caught if not issubclass(w.category, DeprecationWarning)]
    assert [m for m in messages if not m.startswith(EXPECTED_STATE_WARNINGS)] == []


# --------------------------------------------------------------------------- spaces and values
@EACH_OPTION
def test_every_observation_lies_in_its_space(observation: str, obs_format: str) -> None:
    """Every agent's observation at every turn, the final ones included."""
    env = make(observation, obs_format)
    space = env.observation_space("robot_0")
    assert env.observation_spaces == dict.fromkeys(env.possible_agents, space)
    assert env.action_spaces == dict.fromkeys(env.possible_agents, env.action_space("robot_0"))
    turns = 0
    for _ in play(env, seed=1):
        for agent in env.possible_agents:
            obs = env.observe(agent)
            assert space.contains(obs), agent
            assert set(obs) == {"observation", "action_mask"}
        turns += 1
    assert turns == SMALL["num_tasks"] + SMALL["num_robots"]


def test_layouts_and_sizes() -> None:
    m, n = 7, 5
    for observation, obs_format in OPTIONS:
        env = make(observation, obs_format, num_robots=m, queue_len=n)
        features = env.observation_space("robot_0")["observation"]
        layout = env.unwrapped.obs_layout
        if obs_format == "flat":
            expected = 3 * m + 46 * n + 3 if observation == "full" else 46 * n + 3
            assert features.shape == (layout.flat_size,) == (expected,)
        else:
            assert set(features.spaces) == set(FEATURE_KEYS[observation])
        # Scalar (-inf, inf) bounds everywhere (see rtaw_marl.envs.spaces.features_space).
        for box in features.spaces.values() if obs_format == "dict" else [features]:
            assert np.all(box.low == -np.inf)
            assert np.all(box.high == np.inf)
            assert box.dtype == np.float32
        assert env.state_space.shape == (3 * m + 7 * n,)


def test_flat_and_compact_hold_the_same_numbers_as_full_dict() -> None:
    """Same seed and actions: flat = the dict flattened; compact = full less ``robots``."""
    envs = {option: make(*option, num_robots=4) for option in OPTIONS}
    for env in envs.values():
        env.reset(seed=5)
    reference = envs["full", "dict"]
    while not is_done(reference):
        for agent in reference.possible_agents:
            full = reference.observe(agent)
            for (observation, obs_format), env in envs.items():
                obs = env.observe(agent)
                np.testing.assert_array_equal(obs["action_mask"], full["action_mask"])
                features = obs["observation"]
                if obs_format == "flat":
                    features = env.unwrapped.obs_layout.unflatten(features)
                assert tuple(features) == FEATURE_KEYS[observation]
                for key, value in features.items():
                    np.testing.assert_array_equal(value, full["observation"][key])
        slot = first_valid(reference.last()[0])
        for env in envs.values():
            env.step(slot)


def test_state_is_the_robot_table_and_the_queue() -> None:
    env = make(num_robots=4, queue_len=3, num_tasks=9)
    raw = env.unwrapped
    m, n, scale = 4, 3, raw.scale
    for _, obs, *_ in play(env, seed=2):
        state = env.state()
        assert state.dtype == np.float32
        assert env.state_space.contains(state)
        robots, queue = state[: 3 * m].reshape(m, 3), state[3 * m :].reshape(n, 7)
        np.testing.assert_array_equal(robots, obs["observation"]["robots"])
        sim = raw.sim
        np.testing.assert_allclose(queue[:, :4] * scale, sim.queue_rows, atol=1e-4)
        np.testing.assert_allclose(queue[:, 4] * scale, sim.queue_length, atol=1e-4)
        np.testing.assert_allclose(queue[:, 5] * scale, sim.queue_waits(), atol=1e-3)
        np.testing.assert_array_equal(queue[:, 6], sim.queue_mask)
        if not sim.done:
            acting = int(np.flatnonzero(robots[:, 2] == 0.0)[0])
            assert env.agent_selection == f"robot_{acting}"


def test_views_of_all_robots_equal_the_one_robot_function() -> None:
    """Views of all robots at once (one shared ranking) equal each robot's view alone,
    where no two arrivals are exactly equal."""
    rng = np.random.default_rng(0)
    for m in (1, 2, 9, 10, 40):
        n = 6
        distances, remaining = rng.random((m, n)) * 30, rng.random(m) * 10
        lengths, waits, chain = rng.random(n), rng.random(n), rng.random((n, n)) * 20
        mask = rng.random(n) > 0.3
        chain = nearest_other(chain, mask)
        every = np.arange(m)
        rel, riv = relational_features(
            distances, remaining, every, lengths, waits, chain, mask, 23.0
        )
        for robot in range(m):
            one = relational_features(
                distances, remaining, [robot], lengths, waits, chain, mask, 23.0
            )
            np.testing.assert_array_equal(rel[robot], one[0][0])
            np.testing.assert_array_equal(riv[robot], one[1][0])


# --------------------------------------------------------------------------- infos
@pytest.mark.parametrize("mode", ["drain", "paper"])
def test_infos_are_flat_metrics_from_reset(mode: str) -> None:
    fields = [f.name for f in dataclasses.fields(EpisodeMetrics)]
    env = make(episode_mode=mode)
    env.reset(seed=3)
    for agent in env.agents:
        assert list(env.infos[agent]) == fields
        assert env.infos[agent] == zero_info()
        assert all(v == 0 for v in env.infos[agent].values())
    assert isinstance(env.infos["robot_0"]["decisions"], int)
    while not is_done(env):
        assert env.last()[4] == zero_info()
        env.step(first_valid(env.last()[0]))
    final = env.unwrapped.sim.metrics().as_dict()
    assert final["decisions"] == SMALL["num_tasks"]
    assert final["ttd"] > 0
    for agent in env.agents:
        assert env.infos[agent] == final
    while env.agents:
        assert env.last()[4] == final
        env.step(None)
    assert env.last()[4] == final
    env.reset(seed=3)
    assert env.infos["robot_0"] == zero_info()


# --------------------------------------------------------------------------- seeding, versions
def test_np_random_is_seeded_by_reset() -> None:
    a, b = make(), make()
    a.reset(seed=42)
    b.reset(seed=42)
    assert a.unwrapped.np_random_seed == 42
    expected, _ = seeding.np_random(42)
    assert a.unwrapped.np_random.integers(1000) == expected.integers(1000)
    b.unwrapped.np_random.integers(1000)
    # Unseeded resets draw episode seeds from np_random: the same sequence in both.
    a.reset()
    b.reset()
    assert first_valid(a.last()[0]) == first_valid(b.last()[0])
    np.testing.assert_array_equal(a.state(), b.state())
