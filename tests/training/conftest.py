"""Helpers to compose training configs in-process."""

from __future__ import annotations

import pytest

from rtaw_marl.config import compose, to_typed
from rtaw_marl.scenarios import SCENARIOS
from rtaw_marl.training.config import TrainConfig

#: The paper's proof-of-concept simulator settings (appendix), from its scenario.
POC_SIM = dict(SCENARIOS["poc"].sim)
POC_LAYOUT = dict(SCENARIOS["poc"].layout)


#: The learning tests were calibrated with the paper's PPO table and 16 envs per worker;
#: they keep those settings unless a test overrides them.
SMALL_RUN = {"algo": "ppo_paper", "collector.envs_per_worker": "16"}
#: The verdict's 20 evaluation episodes of each, off unless a test is about it.
QUICK = {"verdict": "false"}


def compose_train(overrides: list[str]) -> TrainConfig:
    """The typed rtaw-train config with ``overrides`` (progress bar off)."""
    given = {o.split("=", 1)[0] for o in overrides}
    small = [f"{k}={v}" for k, v in {**SMALL_RUN, **QUICK}.items() if k not in given]
    return to_typed(compose("train", ["progress=false", *small, *overrides]))


@pytest.fixture
def train_cfg():
    return compose_train
