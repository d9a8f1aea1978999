"""A quiet run: with ``progress=false`` training writes no torchrl INFO notes and no
PettingZoo-version warning, on the batched route and on the interop route."""

from __future__ import annotations

import logging
import warnings
from collections.abc import Iterator
from pathlib import Path

import pytest

from rtaw_marl.training.loggers import quiet_torchrl_logs
from rtaw_marl.training.ppo import train

pytestmark = pytest.mark.integration

#: The smallest run that collects, updates (the replay buffer logs at its first fill)
#: and evaluates: the paper's proof of concept, two batches of 256 decisions.
TINY = [
    "scenario=poc", "frames=512", "selection.every_frames=512", "algo.frames_per_batch=256",
    "algo.minibatch_size=128", "algo.epochs=1", "collector.envs_per_worker=4",
    "selection.seeds=[1000]", "logger=none",
]  # fmt: skip


@pytest.fixture
def torchrl_logger(monkeypatch: pytest.MonkeyPatch) -> Iterator[logging.Logger]:
    """torchrl's logger at INFO, as its import leaves it; its level is restored after."""
    monkeypatch.delenv("RL_LOGGING_LEVEL", raising=False)
    logger = logging.getLogger("torchrl")
    level = logger.level
    logger.setLevel(logging.INFO)
    yield logger
    logger.setLevel(level)


class _Records(logging.Handler):
    """Keeps every record that reaches the logger it is attached to."""

    def __init__(self) -> None:
        super().__init__(logging.DEBUG)
        self.records: list[logging.LogRecord] = []

    def emit(self, record: logging.LogRecord) -> None:
        self.records.append(record)


@pytest.mark.parametrize("interop", [False, True], ids=["batched", "interop"])
def test_training_is_quiet(
    train_cfg, tmp_path: Path, torchrl_logger: logging.Logger, interop: bool
) -> None:
    handler = _Records()
    torchrl_logger.addHandler(handler)
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            train(train_cfg([*TINY, f"interop={str(interop).lower()}"]), tmp_path)
    finally:
        torchrl_logger.removeHandler(handler)
    assert [r.getMessage() for r in handler.records if r.levelno < logging.WARNING] == []
    messages = [str(w.message) for w in caught]
    assert not [m for m in messages if "PettingZoo in TorchRL is tested" in m]
    # Warnings a user can act on still get through: torchrl's own logger is not muted.
    assert torchrl_logger.isEnabledFor(logging.WARNING)


def test_rl_logging_level_is_respected(
    torchrl_logger: logging.Logger, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A user who asks torchrl for its INFO lines (``RL_LOGGING_LEVEL``) keeps them."""
    monkeypatch.setenv("RL_LOGGING_LEVEL", "INFO")
    quiet_torchrl_logs()
    assert torchrl_logger.isEnabledFor(logging.INFO)
    monkeypatch.delenv("RL_LOGGING_LEVEL")
    quiet_torchrl_logs()
    assert not torchrl_logger.isEnabledFor(logging.INFO)
    assert torchrl_logger.isEnabledFor(logging.WARNING)
