"""Experiment trackers as :class:`~rtaw_marl.training.logging.RunLogger` backends:
MLflow (``logger=mlflow``) and Weights & Biases (``logger=wandb``).

Neither needs a network by default: MLflow writes a SQLite store in the run folder, W&B
runs offline. Each package is an optional extra, imported only when its logger is chosen.
"""

from __future__ import annotations

import json
import logging
import time
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from rtaw_marl.errors import ConfigError
from rtaw_marl.training.logging_config import (
    FRAMES,
    MLflowLoggerConfig,
    WandbLoggerConfig,
    missing_extra,
)

__all__ = ["MLflowBackend", "WandbBackend", "flat_params"]

#: MLflow's limits: parameters per ``log_batch`` call, characters of a parameter value.
_PARAMS_PER_BATCH = 100
_PARAM_CHARS = 6000


def flat_params(config: Mapping[str, Any], prefix: str = "") -> dict[str, str]:
    """A nested config as MLflow parameters: dotted keys (``algo.lr``), JSON values
    (``null``, ``true``, ``[1000, 1001]``) and strings as they are."""
    out: dict[str, str] = {}
    for key, value in config.items():
        name = f"{prefix}{key}"
        if isinstance(value, Mapping) and value:
            out.update(flat_params(value, f"{name}."))
            continue
        text = value if isinstance(value, str) else json.dumps(value, default=str)
        # Longer values (a long seed list) are cut: MLflow refuses them whole.
        out[name] = text if len(text) <= _PARAM_CHARS else text[: _PARAM_CHARS - 3] + "..."
    return out


@contextmanager
def _quiet(name: str) -> Iterator[None]:
    """``name``'s INFO lines hidden meanwhile (MLflow announces its table migrations)."""
    logger = logging.getLogger(name)
    level = logger.level
    logger.setLevel(max(level, logging.WARNING))
    try:
        yield
    finally:
        logger.setLevel(level)


class MLflowBackend:
    """One MLflow run: the resolved config as parameters, every scalar as a metric.

    Args:
        option: The ``logger=mlflow`` option.
        run_dir: The run folder (the default store lives in ``run_dir/logs``).
        config: The run's resolved config.

    Raises:
        ConfigError: MLflow is not installed, or the tracking store refuses the run.
    """

    def __init__(self, option: MLflowLoggerConfig, run_dir: Path, config: Mapping[str, Any]):
        try:
            from mlflow.entities import Param
            from mlflow.exceptions import MlflowException
            from mlflow.tracking import MlflowClient
        except ImportError as exc:
            raise ConfigError(missing_extra("mlflow", "MLflow", "mlflow")) from exc
        logs = Path(run_dir).resolve() / "logs"
        uri, artifacts = option.tracking_uri, None
        if uri is None:
            logs.mkdir(parents=True, exist_ok=True)
            uri = f"sqlite:///{logs / 'mlflow.db'}"
            # Else MLflow puts artifacts in ./mlartifacts of whatever folder we run in.
            artifacts = (logs / "mlflow-artifacts").as_uri()
        try:
            with _quiet("mlflow"), _quiet("alembic"):
                self._client = MlflowClient(tracking_uri=uri)
                found = self._client.get_experiment_by_name(option.experiment)
                experiment = (
                    found.experiment_id
                    if found is not None
                    else self._client.create_experiment(option.experiment, artifacts)
                )
            tags = {"rtaw.run_dir": str(Path(run_dir).resolve())}
            run = self._client.create_run(
                experiment, run_name=option.run_name or Path(run_dir).name, tags=tags
            )
            self._run_id = run.info.run_id
            params = [Param(k, v) for k, v in flat_params(config).items()]
            for i in range(0, len(params), _PARAMS_PER_BATCH):
                self._client.log_batch(self._run_id, params=params[i : i + _PARAMS_PER_BATCH])
        except MlflowException as exc:
            first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
            raise ConfigError(f"logger=mlflow: {uri}: {first}") from exc
        self.tracking_uri = uri
        self.run_id = self._run_id

    def log(self, scalars: Mapping[str, float], step: int, axis: str | None) -> None:
        """Every scalar but ``axis`` as a metric at step ``scalars[axis]`` or ``step``."""
        from mlflow.entities import Metric

        x = int(scalars[axis]) if axis else int(step)
        now = int(time.time() * 1000)
        metrics = [Metric(k, float(v), now, x) for k, v in scalars.items() if k != axis]
        self._client.log_batch(self._run_id, metrics=metrics)

    def close(self) -> None:
        """Mark the run finished."""
        self._client.set_terminated(self._run_id)


class WandbBackend:
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

    def __init__(self, option: WandbLoggerConfig, run_dir: Path, config: Mapping[str, Any]):
        try:
            import wandb
        except ImportError as exc:
            raise ConfigError(missing_extra("wandb", "wandb", "wandb")) from exc
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
