"""Typed options of the ``logger`` group of ``rtaw-train``: where a run's scalars go.

Plain Python (no torch, no MLflow, no W&B): :mod:`rtaw_marl.config.store` registers
:data:`LOGGER_OPTIONS` with Hydra (the ``logger`` group, YAML twins in
``rtaw_marl/conf/logger/``), and :func:`rtaw_marl.training.loggers.build_logger` builds
the backend registered under the option's name.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from rtaw_marl.errors import ConfigError, lookup
from rtaw_marl.utils.checks import check_fields

__all__ = [
    "FRAMES",
    "LOGGER_OPTIONS",
    "WANDB_MODES",
    "CSVLoggerConfig",
    "LoggerConfig",
    "MLflowLoggerConfig",
    "NoLoggerConfig",
    "TensorBoardLoggerConfig",
    "WandbLoggerConfig",
    "logger_option",
]

#: The step column of the CSV file (and W&B's step metric): PPO frames collected.
FRAMES = "frames"

#: Values of ``logger.mode`` (W&B's own modes).
WANDB_MODES = ("offline", "online", "disabled")


@dataclass(kw_only=True)
class CSVLoggerConfig:
    """``logger=csv`` (the default): one CSV file, ``<run>/logs/metrics.csv``, a header
    row and one row per logged step (docs/training.md, "Logs").

    Attributes:
        name: The option's name.
    """

    name: str = "csv"


@dataclass(kw_only=True)
class TensorBoardLoggerConfig:
    """``logger=tensorboard``: TensorBoard event files in ``<run>/logs`` (the
    ``tensorboard`` extra).

    Attributes:
        name: The option's name.
    """

    name: str = "tensorboard"


@dataclass(kw_only=True)
class NoLoggerConfig:
    """``logger=none``: no scalars are written (checkpoints and the curve still are).

    Attributes:
        name: The option's name.
    """

    name: str = "none"


@dataclass(kw_only=True)
class MLflowLoggerConfig:
    """``logger=mlflow``: an MLflow run with every scalar and the resolved config as
    parameters (the ``mlflow`` extra).

    Attributes:
        name: The option's name.
        tracking_uri: Where the run goes; ``null``: a SQLite store in the run folder,
            ``sqlite:///<run>/logs/mlflow.db`` (no server, no network). A server's
            ``http://host:5000`` or any URI MLflow takes works too.
        experiment: The MLflow experiment (created when missing).
        run_name: The MLflow run's name; ``null``: the run folder's name.
    """

    name: str = "mlflow"
    tracking_uri: str | None = None
    experiment: str = "rtaw_marl"
    run_name: str | None = None

    def __post_init__(self) -> None:
        check_fields(self, "logger.")
        if not self.experiment.strip():
            raise ConfigError("logger.experiment must not be empty")


@dataclass(kw_only=True)
class WandbLoggerConfig:
    """``logger=wandb``: a Weights & Biases run with every scalar and the resolved config
    (the ``wandb`` extra). Offline by default: the run stays in ``<run>/logs/wandb``
    until ``wandb sync`` uploads it.

    Attributes:
        name: The option's name.
        mode: ``offline`` (no network; ``wandb sync <run>/logs/wandb/offline-run-*``
            uploads later), ``online`` (needs ``wandb login``) or ``disabled``.
        project: The W&B project.
        entity: The W&B team or user; ``null``: the logged-in user's default.
        run_name: The W&B run's name; ``null``: the run folder's name.
        tags: Tags of the W&B run.
    """

    name: str = "wandb"
    mode: str = "offline"
    project: str = "rtaw_marl"
    entity: str | None = None
    run_name: str | None = None
    tags: list[str] = field(default_factory=list)

    def __post_init__(self) -> None:
        check_fields(self, "logger.")
        if self.mode not in WANDB_MODES:
            raise ConfigError(
                f"logger.mode must be one of {', '.join(WANDB_MODES)}, got {self.mode!r}"
            )
        if not self.project.strip():
            raise ConfigError("logger.project must not be empty")


LoggerConfig = (
    CSVLoggerConfig
    | TensorBoardLoggerConfig
    | NoLoggerConfig
    | MLflowLoggerConfig
    | WandbLoggerConfig
)

#: ``logger=NAME`` -> its option (registered as ``schema/logger/NAME``); the backend of
#: each is :data:`rtaw_marl.training.loggers.LOGGERS`'s ``NAME``.
LOGGER_OPTIONS: dict[str, type[LoggerConfig]] = {
    "csv": CSVLoggerConfig,
    "tensorboard": TensorBoardLoggerConfig,
    "none": NoLoggerConfig,
    "mlflow": MLflowLoggerConfig,
    "wandb": WandbLoggerConfig,
}


def logger_option(value: object) -> LoggerConfig:
    """A ``logger`` value as its typed option: a name (``"mlflow"``) gets the option's
    defaults; an option passes through.

    Raises:
        ConfigError: An unknown name or a value that is no logger option.
    """
    if isinstance(value, str):
        return lookup(LOGGER_OPTIONS, "logger", value)()
    if isinstance(value, tuple(LOGGER_OPTIONS.values())):
        return value  # type: ignore[return-value]
    raise ConfigError(
        f"logger must be one of {', '.join(LOGGER_OPTIONS)} or its option, got {value!r}"
    )
