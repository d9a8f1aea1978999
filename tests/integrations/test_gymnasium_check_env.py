"""Gymnasium's own ``check_env`` on the single-agent adapter, over every option."""

from __future__ import annotations

import warnings
from typing import Any

import gymnasium
import pytest
from gymnasium.utils.env_checker import check_env

from rtaw_marl import GYMNASIUM_ENV_ID
from rtaw_marl.envs.gymnasium import WarehouseEnv

pytestmark = pytest.mark.integration

SMALL: dict[str, Any] = {
    "num_robots": 3,
    "queue_len": 4,
    "num_tasks": 12,
    "layout": {"name": "open", "width": 12, "height": 9},
    "tasks": "random",
}

#: What the checker says about a sound env: the feature Boxes are unbounded on purpose
#: (docs/environment.md: TorchRL's spec copies), and a text render has no frame rate.
EXPECTED_WARNINGS = (
    "A Box observation space minimum value is -infinity",
    "A Box observation space maximum value is infinity",
    "No render fps was declared",
)


@pytest.mark.parametrize("observation", ["full", "compact"])
@pytest.mark.parametrize("obs_format", ["flat", "dict"])
@pytest.mark.parametrize("mode", ["drain", "paper"])
def test_check_env(
    observation: str, obs_format: str, mode: str, capsys: pytest.CaptureFixture
) -> None:
    """Unwrapped, made through the registry so that the checker also builds every
    render mode from the spec."""
    env = gymnasium.make(
        GYMNASIUM_ENV_ID, observation=observation, obs_format=obs_format, episode_mode=mode, **SMALL
    )
    assert isinstance(env.unwrapped, WarehouseEnv)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        check_env(env.unwrapped)
    messages = {str(w.message) for w in caught}
    assert messages, "the unbounded Boxes are expected to be reported"
    assert [m for m in messages if not any(e in m for e in EXPECTED_WARNINGS)] == []
    assert "decision 0/12" in capsys.readouterr().out  # render_mode="human" printed
