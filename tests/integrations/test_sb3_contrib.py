"""SB3-contrib's ``MaskablePPO`` on the Gymnasium adapter: a short ``learn`` and masked
predictions. The adapter's ``action_masks()`` is the mask MaskablePPO reads."""

from __future__ import annotations

from typing import Any

import gymnasium
import numpy as np
import pytest

pytest.importorskip("sb3_contrib")

from sb3_contrib import MaskablePPO
from sb3_contrib.common.maskable.utils import get_action_masks

from rtaw_marl import GYMNASIUM_ENV_ID
from rtaw_marl.sim.inputs import training_seed

pytestmark = pytest.mark.integration

SMALL: dict[str, Any] = {
    "num_robots": 3,
    "queue_len": 4,
    "num_tasks": 12,
    "layout": {"name": "open", "width": 12, "height": 9},
    "tasks": "random",
}


def test_maskable_ppo_learns_and_predicts_legal_slots() -> None:
    env = gymnasium.make(GYMNASIUM_ENV_ID, **SMALL)
    model = MaskablePPO(
        "MlpPolicy",
        env,
        n_steps=64,
        batch_size=32,
        n_epochs=2,
        policy_kwargs={"net_arch": [32]},
        # SB3 also resets the env with this seed: a training seed, never an evaluation one.
        seed=training_seed(0),
        device="cpu",
    )
    # 256 steps: about 21 episodes of 12 decisions; an illegal slot would raise.
    model.learn(total_timesteps=256)
    assert model.num_timesteps == 256
    episodes = list(model.ep_info_buffer)
    assert len(episodes) >= 20
    assert all(ep["l"] == SMALL["num_tasks"] and ep["r"] < 0 for ep in episodes)
    # The masks through SB3's VecEnv (Monitor and Gymnasium's wrappers in between).
    np.testing.assert_array_equal(get_action_masks(model.get_env()), [[True] * 4])

    obs, info = env.reset(seed=3)
    for _ in range(SMALL["num_tasks"] - 1):
        # Only the last legal slot allowed: the prediction must be that slot.
        only = np.zeros(4, dtype=bool)
        only[np.flatnonzero(info["action_mask"])[-1]] = True
        action, _ = model.predict(obs, action_masks=only, deterministic=True)
        assert only[action]
        obs, _, terminated, _, info = env.step(action)
        assert not terminated
    action, _ = model.predict(obs, action_masks=env.unwrapped.action_masks())
    assert env.step(action)[2]
