"""Run logging: one CSV file by default; TensorBoard, MLflow or W&B on request; torchrl's
console notes hidden.

Each ``logger=NAME`` option (:mod:`.config`, the Hydra ``logger`` group) has one backend
registered in :data:`LOGGERS`; :func:`build_logger` builds the run's :class:`RunLogger`
around it, which the training loop calls as ``log(scalars, step)`` with ``step`` the
frames collected so far. Every backend gets the same calls.

Modules: :mod:`.base` (:class:`Backend`, ``logger=none``, :class:`RunLogger`),
:mod:`.csv_log`, :mod:`.tensorboard_log`, :mod:`.mlflow_log`, :mod:`.wandb_log` (one per
backend; a package beyond the ``train`` extra is imported only when its logger is
chosen), :mod:`.config` (the typed options, plain Python), :mod:`.reachable` (is a
tracking server there, asked before the run) and :mod:`.console`.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

from rtaw_marl.errors import ConfigError, unknown_name
from rtaw_marl.training.loggers.base import Backend, NoBackend, RunLogger
from rtaw_marl.training.loggers.config import (
    FRAMES,
    LOGGER_OPTIONS,
    LoggerConfig,
    logger_option,
)
from rtaw_marl.training.loggers.console import quiet_torchrl_logs
from rtaw_marl.training.loggers.csv_log import METRICS_CSV, CSVMetrics, read_metrics
from rtaw_marl.training.loggers.mlflow_log import MLflowBackend
from rtaw_marl.training.loggers.tensorboard_log import TensorBoardBackend
from rtaw_marl.training.loggers.wandb_log import WandbBackend

__all__ = [
    "FRAMES",
    "LOGGERS",
    "METRICS_CSV",
    "Backend",
    "CSVMetrics",
    "RunLogger",
    "build_logger",
    "check_installed",
    "quiet_torchrl_logs",
    "read_metrics",
]

#: ``logger=NAME`` -> its backend (the same names as :data:`.config.LOGGER_OPTIONS`).
LOGGERS: dict[str, type[Backend]] = {
    CSVMetrics.name: CSVMetrics,
    TensorBoardBackend.name: TensorBoardBackend,
    NoBackend.name: NoBackend,
    MLflowBackend.name: MLflowBackend,
    WandbBackend.name: WandbBackend,
}


def _backend(option: LoggerConfig | str) -> tuple[LoggerConfig, type[Backend]]:
    """``option`` as its typed option and its registered backend."""
    option = logger_option(option)
    if option.name not in LOGGERS:
        raise unknown_name("logger", option.name, list(LOGGERS))
    if not isinstance(option, LOGGER_OPTIONS[option.name]):
        raise ConfigError(
            f"logger.name={option.name!r} does not match its option "
            f"{type(option).__name__}: choose the logger with logger={option.name}"
        )
    return option, LOGGERS[option.name]


def build_logger(
    run_dir: Path,
    option: LoggerConfig | str = "csv",
    config: Mapping[str, Any] | None = None,
) -> RunLogger:
    """The run's logger: the backend registered under ``option``'s name.

    Args:
        run_dir: The run folder; every backend writes under ``run_dir/logs`` unless its
            option points elsewhere (``logger.tracking_uri``, ``logger.mode=online``).
        option: A ``logger`` option or its name (``"csv"``, ``"tensorboard"``,
            ``"mlflow"``, ``"wandb"``, ``"none"``).
        config: The run's resolved config (plain dicts), recorded by MLflow (as
            parameters) and W&B (as the run's config).

    Raises:
        ConfigError: An unknown name (the message lists :data:`LOGGERS`), or its
            package is not installed (the message names the extra to install), or its
            tracking store refuses the run.
    """
    option, backend = _backend(option)
    return RunLogger(backend.start(option, Path(run_dir), config or {}))


def check_installed(option: LoggerConfig | str) -> None:
    """Fail before a run starts when its logger cannot work: its tracking server does
    not answer (``logger.tracking_uri``, asked once with a short timeout), or its
    package is not installed.

    The server is asked first, before the package is imported, so a server that is not
    there is one line in seconds, with or without the package.

    Raises:
        ConfigError: The server does not answer (the message names the option and the
            reason), the package is missing (the message names the extra), or an
            unknown name.
    """
    option, backend = _backend(option)
    backend.check_reachable(option)
    backend.check_installed()
