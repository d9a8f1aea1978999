"""``logger=wandb``: a Weights & Biases run with every scalar and the resolved config
(the ``wandb`` extra, imported only when this logger is chosen).

No network by default: the run is offline, in the run folder, until ``wandb sync``.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

from rtaw_marl.errors import ConfigError
from rtaw_marl.training.loggers.base import Backend
from rtaw_marl.training.loggers.config import FRAMES, LoggerConfig, WandbLoggerConfig

__all__ = ["WandbBackend"]


class WandbBackend(Backend):
    """One W&B run: the resolved config as its config, every scalar in its history.

    Scalars are plotted against ``frames`` (W&B's ``define_metric``); the imitation warm
    start's against ``imitation/decisions``.

    Args:
        option: The ``logger=wandb`` option.
        run_dir: The run folder; W&B writes ``run_dir/logs/wandb/<mode>-run-*``.
        config: The run's resolved config.

    Raises:
        ConfigError: wandb is not installed, or W&B refuses to start the run (online
            without ``wandb login``).
    """

    name = "wandb"
    requires = ("wandb", "wandb")

    def __init__(self, option: WandbLoggerConfig, run_dir: Path, config: Mapping[str, Any]):
        try:
            import wandb
        except ImportError as exc:
            raise self.not_installed() from exc
        logs = Path(run_dir).resolve() / "logs"
        logs.mkdir(parents=True, exist_ok=True)
        # No console capture, system sampling, git or code snapshots: scalars and config.
        settings = wandb.Settings(
            console="off", silent=True, x_disable_stats=True, disable_git=True, save_code=False
        )
        try:
            self._run = wandb.init(
                project=option.project, entity=option.entity, mode=option.mode,
                name=option.run_name or Path(run_dir).name, tags=list(option.tags),
                dir=str(logs), config=dict(config), settings=settings, reinit="create_new",
            )  # fmt: skip
        except wandb.errors.Error as exc:
            first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
            raise ConfigError(f"logger=wandb: {first}") from exc
        self._run.define_metric(FRAMES)
        self._defined: set[str] = {FRAMES}

    @classmethod
    def start(cls, option: LoggerConfig, run_dir: Path, config: Mapping[str, Any]) -> WandbBackend:
        """A new W&B run (``option``: its :class:`WandbLoggerConfig`)."""
        return cls(option, run_dir, config)  # type: ignore[arg-type]

    def log(self, scalars: Mapping[str, float], step: int, axis: str | None) -> None:
        """One history row: ``scalars`` and ``frames`` (or only ``scalars`` on ``axis``)."""
        for name in scalars:
            if name not in self._defined:
                if name == axis:
                    self._run.define_metric(name)
                else:
                    self._run.define_metric(name, step_metric=axis or FRAMES)
                self._defined.add(name)
        row = {k: float(v) for k, v in scalars.items()}
        if axis is None:
            row[FRAMES] = int(step)
        self._run.log(row)

    def close(self) -> None:
        """Finish the run (offline: its folder is complete and ``wandb sync`` can upload)."""
        self._run.finish()
