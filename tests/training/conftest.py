"""Helpers to compose training configs in-process."""

from __future__ import annotations

import pytest
from hydra import compose, initialize_config_dir
from omegaconf import DictConfig

from rtaw_marl.cli import CONF_DIR


def compose_train(overrides: list[str]) -> DictConfig:
    """The rtaw-train config with ``overrides`` (progress bar off)."""
    with initialize_config_dir(config_dir=str(CONF_DIR), version_base="1.3"):
        return compose(config_name="train", overrides=["progress=false", *overrides])


@pytest.fixture
def train_cfg():
    return compose_train
