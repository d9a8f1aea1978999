"""SuperSuit's Box observation wrappers (``flatten_v0``, ``normalize_obs_v0``,
``dtype_v0``) on the flat layout, driven by a masked random policy.

Two facts shape how (docs/integrations.md): SuperSuit's Box wrappers take a ``Box``
observation, and the AEC env's is PettingZoo's masked ``Dict`` (``obs_format="flat"``
makes its ``"observation"`` entry a Box), so the entry is taken out first with SuperSuit's
own ``observation_lambda_v0`` and the mask read from ``env.unwrapped``; and
``normalize_obs_v0`` needs finite bounds, which the features do not have (times and
waits are unbounded), so a squash (``tanh``, ``(-inf, inf) -> (-1, 1)``) comes first.
The Gymnasium adapter's observation is the Box itself.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from gymnasium.spaces import Box

from rtaw_marl import warehouse_v1
from rtaw_marl.envs.gymnasium import WarehouseEnv

pytestmark = pytest.mark.integration

ss = pytest.importorskip("supersuit")

SMALL: dict[str, Any] = {
    "num_robots": 3,
    "queue_len": 4,
    "num_tasks": 12,
    "layout": {"name": "open", "width": 12, "height": 9},
    "tasks": "random",
}


def features(obs: dict[str, np.ndarray], space: Any) -> np.ndarray:
    return obs["observation"]


def squash(obs: np.ndarray, space: Any) -> np.ndarray:
    return np.tanh(obs)


def box_wrappers(env: Any) -> Any:
    """``tanh`` squash, then SuperSuit's ``flatten_v0``, ``normalize_obs_v0``, ``dtype_v0``."""
    env = ss.observation_lambda_v0(env, squash)
    return ss.dtype_v0(ss.normalize_obs_v0(ss.flatten_v0(env)), np.float64)


@pytest.mark.parametrize("observation", ["full", "compact"])
def test_box_wrappers_on_the_aec_env(observation: str) -> None:
    base = warehouse_v1.env(observation=observation, obs_format="flat", **SMALL)
    env = box_wrappers(ss.observation_lambda_v0(base, features, lambda space: space["observation"]))
    size = base.unwrapped.obs_layout.flat_size
    assert env.observation_space("robot_0") == Box(0.0, 1.0, (size,), np.float64)
    rng = np.random.default_rng(0)
    env.reset(seed=0)
    steps = episodes = 0
    while steps < 300:
        for agent in env.agent_iter():
            obs, _, terminated, truncated, _ = env.last()
            assert env.observation_space(agent).contains(obs)
            if terminated or truncated:
                action = None
            else:
                mask = env.unwrapped.observe(agent)["action_mask"]
                action = int(rng.choice(np.flatnonzero(mask)))
                steps += 1
            env.step(action)
        episodes += 1
        env.reset()
    assert episodes == steps // SMALL["num_tasks"]


def test_box_wrappers_on_the_gymnasium_adapter() -> None:
    env = box_wrappers(WarehouseEnv(**SMALL))
    assert env.observation_space == Box(0.0, 1.0, (3 * 3 + 46 * 4 + 3,), np.float64)
    rng = np.random.default_rng(0)
    obs, info = env.reset(seed=0)
    for _ in range(300):
        assert env.observation_space.contains(obs)
        action = int(rng.choice(np.flatnonzero(info["action_mask"])))
        obs, _, terminated, truncated, info = env.step(action)
        if terminated or truncated:
            obs, info = env.reset()


def test_what_does_not_apply_as_documented() -> None:
    """No finite bounds for normalize_obs_v0; the masked Dict is no Box."""
    with pytest.raises(AssertionError, match="infinite bounds"):
        ss.normalize_obs_v0(WarehouseEnv(**SMALL))
    with pytest.raises(AttributeError, match="low"):
        ss.flatten_v0(warehouse_v1.env(obs_format="flat", **SMALL))
