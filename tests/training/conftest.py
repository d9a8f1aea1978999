"""Helpers to compose training configs in-process."""

from __future__ import annotations

import pytest

from rtaw_marl.config import compose, to_typed
from rtaw_marl.training.config import TrainConfig

#: The paper's proof-of-concept simulator settings (appendix).
POC_ENV = {
    "num_robots": 2,
    "num_tasks": 5,
    "queue_len": 2,
    "noise_mean": 0.0,
    "noise_var": 0.0,
    "robot_starts": [[2, 2], [6, 2]],
    "robot_free_times": [0.0, 2.0],
}
POC_LAYOUT = {"name": "open", "width": 10, "height": 10}


#: The learning tests were calibrated with the paper's PPO table and 16 envs per worker;
#: they keep those settings unless a test overrides them.
SMALL_RUN = {"algo": "ppo_paper", "collector.envs_per_worker": "16"}


def compose_train(overrides: list[str]) -> TrainConfig:
    """The typed rtaw-train config with ``overrides`` (progress bar off)."""
    given = {o.split("=", 1)[0] for o in overrides}
    small = [f"{k}={v}" for k, v in SMALL_RUN.items() if k not in given]
    return to_typed(compose("train", ["progress=false", *small, *overrides]))


@pytest.fixture
def train_cfg():
    return compose_train
