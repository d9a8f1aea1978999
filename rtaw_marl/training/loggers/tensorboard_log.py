"""``logger=tensorboard``: TensorBoard event files in ``<run>/logs`` through torchrl's
logger (the ``tensorboard`` extra, imported only when this logger is chosen)."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

from rtaw_marl.training.loggers.base import Backend
from rtaw_marl.training.loggers.config import LoggerConfig

__all__ = ["TensorBoardBackend"]


class TensorBoardBackend(Backend):
    """TensorBoard event files through torchrl's logger (the ``tensorboard`` extra).

    Args:
        folder: Where the event files go (torchrl adds the ``train`` experiment folder).

    Raises:
        ConfigError: TensorBoard is not installed.
    """

    name = "tensorboard"
    requires = ("tensorboard", "TensorBoard")

    def __init__(self, folder: Path) -> None:
        try:
            from torchrl.record.loggers.tensorboard import TensorboardLogger

            self._logger = TensorboardLogger(exp_name="train", log_dir=str(folder))
        except ImportError as exc:
            raise self.not_installed() from exc

    @classmethod
    def start(
        cls, option: LoggerConfig, run_dir: Path, config: Mapping[str, Any]
    ) -> TensorBoardBackend:
        """Event files in ``run_dir/logs``."""
        return cls(Path(run_dir) / "logs")

    def log(self, scalars: Mapping[str, float], step: int, axis: str | None) -> None:
        """Every scalar but ``axis`` at step ``scalars[axis]`` or ``step``."""
        x = int(scalars[axis]) if axis else step
        for name, value in scalars.items():
            if name != axis:
                self._logger.log_scalar(name, float(value), step=x)

    def close(self) -> None:
        """torchrl's writer flushes on its own."""
