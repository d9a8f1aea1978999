"""Helpers to compose training configs in-process."""

from __future__ import annotations

import pytest
from hydra import compose, initialize_config_dir
from omegaconf import DictConfig

from rtaw_marl.cli import CONF_DIR

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


def compose_train(overrides: list[str]) -> DictConfig:
    """The rtaw-train config with ``overrides`` (progress bar off)."""
    with initialize_config_dir(config_dir=str(CONF_DIR), version_base="1.3"):
        return compose(config_name="train", overrides=["progress=false", *overrides])


@pytest.fixture
def train_cfg():
    return compose_train
