"""Run logging: CSV by default, TensorBoard on request; torchrl's console notes hidden."""

from __future__ import annotations

import logging
import os
from collections.abc import Mapping
from pathlib import Path

from rtaw_marl.errors import ConfigError

__all__ = ["LOGGERS", "RunLogger", "quiet_torchrl_logs"]

LOGGERS = ("csv", "tensorboard", "none")


class RunLogger:
    """Scalars through torchrl's loggers, into ``run_dir/logs``.

    Args:
        run_dir: The run folder.
        kind: ``"csv"`` (default), ``"tensorboard"`` or ``"none"``.
    """

    def __init__(self, run_dir: Path, kind: str = "csv") -> None:
        if kind not in LOGGERS:
            raise ConfigError(f"logger must be one of {', '.join(LOGGERS)}, got {kind!r}")
        self._logger = None
        if kind == "csv":
            from torchrl.record.loggers.csv import CSVLogger

            self._logger = CSVLogger(exp_name="train", log_dir=str(run_dir / "logs"))
        elif kind == "tensorboard":
            try:
                from torchrl.record.loggers.tensorboard import TensorboardLogger

                self._logger = TensorboardLogger(exp_name="train", log_dir=str(run_dir / "logs"))
            except ImportError as exc:
                raise ConfigError(
                    "logger=tensorboard needs the tensorboard package: "
                    "pip install -e '.[tensorboard]'"
                ) from exc

    def log(self, scalars: Mapping[str, float], step: int) -> None:
        """Log every scalar at ``step`` (frames collected)."""
        if self._logger is None:
            return
        for name, value in scalars.items():
            self._logger.log_scalar(name, float(value), step=step)

    def close(self) -> None:
        """Flush the CSV files (torchrl's CSV logger writes on each call)."""


def quiet_torchrl_logs() -> None:
    """Hide torchrl's INFO console lines; its warnings and errors still show.

    torchrl logs notes such as ``Initialized LazyTensorStorage with ... shape`` at INFO,
    in colour, on stdout; a user can do nothing about them. A level set through
    ``RL_LOGGING_LEVEL`` (torchrl's own switch, read at its import) is left as it is.
    """
    if "RL_LOGGING_LEVEL" in os.environ:
        return
    import torchrl  # noqa: F401  (its import sets the level to INFO: lower it after that)

    logger = logging.getLogger("torchrl")
    if logger.getEffectiveLevel() < logging.WARNING:
        logger.setLevel(logging.WARNING)
