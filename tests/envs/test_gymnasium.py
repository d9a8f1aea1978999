"""The single-agent Gymnasium adapter against its docstring spec.

The PettingZoo env is the oracle: the same seed gives the same episode, so every
observation, reward, flag and metric of the adapter must match the AEC env's for the
robot that acts. (Gymnasium's ``check_env`` runs in tests/integrations.)
"""

from __future__ import annotations

import subprocess
import sys
from collections.abc import Iterator
from typing import Any

import gymnasium
import numpy as np
import pytest

from rtaw_marl import GYMNASIUM_ENV_ID, warehouse_v1
from rtaw_marl.envs.gymnasium import WarehouseEnv
from rtaw_marl.errors import ConfigError, InvalidActionError, ResetNeededError

pytestmark = pytest.mark.unit

SMALL: dict[str, Any] = {
    "num_robots": 3,
    "queue_len": 4,
    "num_tasks": 12,
    "layout": {"name": "open", "width": 12, "height": 9},
    "tasks": "random",
}
OPTIONS = [(obs, fmt) for obs in ("full", "compact") for fmt in ("flat", "dict")]


def first_legal(mask: np.ndarray) -> int:
    return int(np.flatnonzero(mask)[0])


def episode(env: WarehouseEnv, seed: int | None) -> Iterator[tuple[Any, ...]]:
    """``(obs, info)`` of the reset, then ``(obs, reward, terminated, truncated, info)``
    per step of one episode under the first-legal-slot policy."""
    obs, info = env.reset(seed=seed)
    yield obs, info
    done = False
    while not done:
        step = env.step(first_legal(info["action_mask"]))
        obs, _, terminated, truncated, info = step
        done = terminated or truncated
        yield step


def assert_same_features(a: Any, b: Any) -> None:
    if isinstance(a, dict):
        assert a.keys() == b.keys()
        for key in a:
            np.testing.assert_array_equal(a[key], b[key])
    else:
        np.testing.assert_array_equal(a, b)


# --------------------------------------------------------------------------- registration
def test_make_builds_the_adapter_with_its_kwargs() -> None:
    env = gymnasium.make(GYMNASIUM_ENV_ID, observation="compact", num_robots=5, queue_len=3)
    assert isinstance(env.unwrapped, WarehouseEnv)
    assert env.unwrapped.sim.num_robots == 5
    assert env.action_space == gymnasium.spaces.Discrete(3)
    assert env.observation_space.shape == (46 * 3 + 3,)
    assert env.spec is not None
    assert env.spec.max_episode_steps is None


def test_registration_from_a_fresh_interpreter() -> None:
    """``import gymnasium, rtaw_marl`` registers the id; the ``module:id`` form always works."""
    code = (
        "import gymnasium, rtaw_marl; gymnasium.make('rtaw/warehouse-single-v1');"
        "import sys; sys.modules.pop('rtaw_marl.envs.gymnasium');"
        "gymnasium.registry.pop('rtaw/warehouse-single-v1');"
        "gymnasium.make('rtaw_marl.envs.gymnasium:rtaw/warehouse-single-v1'); print('ok')"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "ok"


# --------------------------------------------------------------------------- the AEC env as oracle
@pytest.mark.parametrize(("observation", "obs_format"), OPTIONS)
@pytest.mark.parametrize("mode", ["drain", "paper"])
def test_same_episode_as_the_pettingzoo_env(observation: str, obs_format: str, mode: str) -> None:
    """Observation = the acting agent's ``observe()["observation"]``, reward = that
    agent's reward for the decision (``rewards[agent]`` right after its step)."""
    kwargs = {**SMALL, "observation": observation, "episode_mode": mode}
    gym_env = WarehouseEnv(obs_format=obs_format, **kwargs)
    aec = warehouse_v1.env(obs_format=obs_format, **kwargs)
    aec.reset(seed=5)
    obs, info = gym_env.reset(seed=5)
    terminated = truncated = False
    while True:
        aec_obs, _, aec_terminated, aec_truncated, aec_info = aec.last()
        assert_same_features(obs, aec_obs["observation"])
        np.testing.assert_array_equal(info["action_mask"], aec_obs["action_mask"])
        assert (terminated, truncated) == (aec_terminated, aec_truncated)
        assert info == {"action_mask": info["action_mask"], **aec_info}
        if terminated or truncated:
            break
        acting = aec.agent_selection
        slot = first_legal(info["action_mask"])
        aec.step(slot)
        obs, reward, terminated, truncated, info = gym_env.step(slot)
        assert reward == aec.rewards[acting]
    assert terminated == (mode == "drain")
    assert truncated == (mode == "paper")
    assert info["decisions"] == SMALL["num_tasks"]


def test_reward_is_minus_the_travel_delay_of_the_decision_taken() -> None:
    """On an open grid with A*, the travel delay is the ``k`` the acting robot saw for the
    slot it chose (``tasks[:, 4] * L``): the reward belongs to this step's decision."""
    open_16 = {"name": "open", "width": 16, "height": 16}
    env = WarehouseEnv(
        obs_format="dict", num_robots=4, num_tasks=40, queue_len=5, layout=open_16, tasks="random"
    )
    scale = env.unwrapped.sim.layout.scale
    rng = np.random.default_rng(0)
    obs, info = env.reset(seed=3)
    total, terminated = 0.0, False
    while not terminated:
        slot = int(rng.choice(np.flatnonzero(info["action_mask"])))
        expected = -float(obs["tasks"][slot, 4]) * scale
        obs, reward, terminated, _, info = env.step(slot)
        assert reward == pytest.approx(expected, rel=1e-6)
        total += reward
    assert total == pytest.approx(-info["ttd"], rel=1e-9)


# --------------------------------------------------------------------------- masks and actions
def test_action_masks_and_info_mask_agree() -> None:
    env = WarehouseEnv(**{**SMALL, "num_tasks": 6})
    for step in episode(env, seed=2):
        info = step[-1]
        mask = info["action_mask"]
        assert mask.dtype == np.int8
        masks = env.action_masks()
        assert masks.dtype == np.bool_
        np.testing.assert_array_equal(masks, mask.astype(bool))
        if mask.any():
            assert mask[env.action_space.sample(mask=mask)] == 1
    # After the last decision nothing is legal; drain mode has emptied slots before.
    assert not env.action_masks().any()


@pytest.mark.parametrize("action", [2, 3, 4, -1, 1.0, "1", None, np.array([0])], ids=repr)
def test_invalid_actions_raise_and_change_nothing(action: Any) -> None:
    env = WarehouseEnv(**{**SMALL, "num_tasks": 2})
    with pytest.raises(
        ResetNeededError, match=r"env\.step\(\) before reset\(\): call env\.reset\(\) first"
    ):
        env.step(0)
    _, info = env.reset(seed=0)
    np.testing.assert_array_equal(info["action_mask"], [1, 1, 0, 0])
    with pytest.raises(InvalidActionError):
        env.step(action)
    assert env.sim.decisions == 0
    env.step(np.int64(1))
    env.step(0)
    with pytest.raises(InvalidActionError, match="episode is over"):
        env.step(0)


# --------------------------------------------------------------------------- seeding
def test_seeded_reset_reseeds_np_random_and_fixes_the_episode() -> None:
    a, b = WarehouseEnv(**SMALL), WarehouseEnv(**SMALL)
    first = [step[0] for step in episode(a, seed=42)]
    assert a.np_random_seed == 42
    again = [step[0] for step in episode(b, seed=np.int64(42))]
    for x, y in zip(first, again, strict=True):
        np.testing.assert_array_equal(x, y)
    # Unseeded resets draw the episode from np_random: the same sequence in both.
    np.testing.assert_array_equal(a.reset()[0], b.reset()[0])
    other, _ = a.reset(seed=43)
    assert not np.array_equal(other, first[0])


@pytest.mark.parametrize("seed", [-1, 1.5, "a", True, [1]], ids=repr)
def test_bad_seeds_raise_config_errors(seed: Any) -> None:
    env = WarehouseEnv(**SMALL)
    with pytest.raises(ConfigError, match=r"seed must be an integer >= 0"):
        env.reset(seed=seed)
    env.reset(seed=0)


# --------------------------------------------------------------------------- options, rendering
def test_unknown_options_raise_config_errors() -> None:
    with pytest.raises(ConfigError, match="render_mode"):
        WarehouseEnv(render_mode="rgb_array")
    with pytest.raises(ConfigError, match="obs_format"):
        WarehouseEnv(obs_format="tuple")
    with pytest.raises(ConfigError, match="num_robot"):
        WarehouseEnv(num_robot=3)


def test_render_ansi_is_the_pettingzoo_text_and_human_prints_each_step(
    capsys: pytest.CaptureFixture,
) -> None:
    env = WarehouseEnv(render_mode="ansi", **SMALL)
    aec = warehouse_v1.env(render_mode="ansi", **SMALL)
    env.reset(seed=1)
    aec.reset(seed=1)
    assert env.render() == aec.render()
    assert WarehouseEnv(**SMALL).render() is None
    human = WarehouseEnv(render_mode="human", **SMALL)
    human.reset(seed=1)
    human.step(0)
    out = capsys.readouterr().out
    assert out.count("decision ") == 2
    assert out.startswith(env.render())


def test_the_old_id_still_makes_the_adapter_with_a_warning() -> None:
    import gymnasium

    import rtaw_marl

    rtaw_marl.register_envs()
    with pytest.warns(DeprecationWarning, match="use rtaw/warehouse-single-v1"):
        env = gymnasium.make("rtaw/Warehouse-v1", num_robots=3, num_tasks=5)
    assert env.unwrapped.__class__.__name__ == "WarehouseEnv"
    assert gymnasium.make("rtaw/warehouse-single-v1", num_robots=3, num_tasks=5)


def test_a_named_scenario_builds_as_in_the_aec_env() -> None:
    """``scenario=`` works in the Gymnasium adapter as in the PettingZoo env: the same
    simulator, the keys given on top."""
    from rtaw_marl import warehouse_v1
    from rtaw_marl.envs.gymnasium import WarehouseEnv

    single = WarehouseEnv(scenario="C_astar_m10", num_tasks=40)
    aec = warehouse_v1.env(scenario="C_astar_m10", num_tasks=40).unwrapped
    assert single.sim.config == aec.sim.config
    assert single.sim.layout.describe() == aec.sim.layout.describe()
    assert single.sim.config.num_tasks == 40
    with pytest.raises(ConfigError, match="unknown scenario 'C_astar_m1'"):
        WarehouseEnv(scenario="C_astar_m1")
