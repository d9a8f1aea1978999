"""``logger=mlflow``: an MLflow run with every scalar and the resolved config as its
parameters (the ``mlflow`` extra, imported only when this logger is chosen).

No network by default: the run goes to a SQLite store in the run folder. A server's
``http(s)`` URI is asked once before the run starts (:meth:`MLflowBackend.check_reachable`),
so a server that is not there costs a few seconds and one line, not minutes of retries.
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
from rtaw_marl.training.loggers.base import Backend
from rtaw_marl.training.loggers.config import LoggerConfig, MLflowLoggerConfig
from rtaw_marl.training.loggers.reachable import check_http_server

__all__ = ["MLflowBackend", "flat_params"]

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


class MLflowBackend(Backend):
    """One MLflow run: the resolved config as parameters, every scalar as a metric.

    Args:
        option: The ``logger=mlflow`` option.
        run_dir: The run folder (the default store lives in ``run_dir/logs``).
        config: The run's resolved config.

    Raises:
        ConfigError: MLflow is not installed, or the tracking store refuses the run.
    """

    name = "mlflow"
    requires = ("mlflow", "MLflow")

    def __init__(self, option: MLflowLoggerConfig, run_dir: Path, config: Mapping[str, Any]):
        try:
            from mlflow.entities import Param
            from mlflow.exceptions import MlflowException
            from mlflow.tracking import MlflowClient
        except ImportError as exc:
            raise self.not_installed() from exc
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

    @classmethod
    def check_reachable(cls, option: LoggerConfig) -> None:
        """Refuse an ``http(s)`` ``logger.tracking_uri`` whose server does not answer in
        a few seconds (:func:`~.reachable.check_http_server`): MLflow's client would
        retry it silently for minutes (259 s) before failing."""
        uri = getattr(option, "tracking_uri", None)
        if uri is not None:
            check_http_server(uri, "logger.tracking_uri")

    @classmethod
    def start(cls, option: LoggerConfig, run_dir: Path, config: Mapping[str, Any]) -> MLflowBackend:
        """A new MLflow run (``option``: its :class:`MLflowLoggerConfig`)."""
        return cls(option, run_dir, config)  # type: ignore[arg-type]

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
