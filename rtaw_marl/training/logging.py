"""Run logging: one CSV file by default; TensorBoard, MLflow or W&B on request; torchrl's
console notes hidden.

:class:`RunLogger` is what the training loop sees: ``log(scalars, step)`` with ``step``
the frames collected so far. Every backend gets the same calls; the ``logger`` option
(:mod:`rtaw_marl.training.logging_config`) picks one.
"""

from __future__ import annotations

import csv
import importlib
import io
import logging
import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any, Protocol

from rtaw_marl.errors import ConfigError
from rtaw_marl.training.logging_config import (
    FRAMES,
    CSVLoggerConfig,
    LoggerConfig,
    MLflowLoggerConfig,
    TensorBoardLoggerConfig,
    WandbLoggerConfig,
    logger_option,
    missing_extra,
)
from rtaw_marl.utils.atomic import atomic_write

__all__ = [
    "FRAMES",
    "METRICS_CSV",
    "CSVMetrics",
    "RunLogger",
    "check_installed",
    "quiet_torchrl_logs",
    "read_metrics",
]

#: The CSV logger's file, relative to the run folder.
METRICS_CSV = Path("logs") / "metrics.csv"


class Backend(Protocol):
    """What a logger backend does with :class:`RunLogger`'s calls."""

    def log(self, scalars: Mapping[str, float], step: int, axis: str | None) -> None:
        """Record ``scalars`` at ``step`` frames (``axis``: see :meth:`RunLogger.log`)."""

    def close(self) -> None:
        """Flush and end the run."""


class RunLogger:
    """A run's scalars, into the backend its ``logger`` option names.

    Args:
        run_dir: The run folder; every backend writes under ``run_dir/logs`` unless its
            option points elsewhere (``logger.tracking_uri``, ``logger.mode=online``).
        option: A ``logger`` option or its name (``"csv"``, ``"tensorboard"``,
            ``"mlflow"``, ``"wandb"``, ``"none"``).
        config: The run's resolved config (plain dicts), recorded by MLflow (as
            parameters) and W&B (as the run's config).

    Raises:
        ConfigError: An unknown option, or its package is not installed (the message
            names the extra to install), or its tracking store refuses the run.
    """

    def __init__(
        self,
        run_dir: Path,
        option: LoggerConfig | str = "csv",
        config: Mapping[str, Any] | None = None,
    ) -> None:
        option = logger_option(option)
        run_dir = Path(run_dir)
        self._backend: Backend | None = None
        if isinstance(option, CSVLoggerConfig):
            self._backend = CSVMetrics(run_dir / METRICS_CSV)
        elif isinstance(option, TensorBoardLoggerConfig):
            self._backend = _TensorBoard(run_dir / "logs")
        elif isinstance(option, MLflowLoggerConfig):
            from rtaw_marl.training.logging_tracking import MLflowBackend

            self._backend = MLflowBackend(option, run_dir, config or {})
        elif isinstance(option, WandbLoggerConfig):
            from rtaw_marl.training.logging_tracking import WandbBackend

            self._backend = WandbBackend(option, run_dir, config or {})

    def log(self, scalars: Mapping[str, float], step: int, axis: str | None = None) -> None:
        """Log every scalar at ``step`` (frames collected).

        Args:
            scalars: Name -> value.
            step: PPO frames collected so far.
            axis: The name of one of ``scalars`` that is the others' own x axis, for
                scalars that do not advance with frames (the imitation warm start's
                ``imitation/decisions``, logged at frame 0): backends that plot one
                series per scalar (TensorBoard, MLflow, W&B) use it as their step.
        """
        if self._backend is not None and scalars:
            self._backend.log(scalars, step, axis)

    def close(self) -> None:
        """End the MLflow or W&B run (the CSV file is complete already)."""
        if self._backend is not None:
            self._backend.close()
            self._backend = None


class CSVMetrics:
    """Every scalar of a run in one CSV file: a header row, then one row per step.

    Columns: ``frames`` first, then each scalar in the order it was first logged. A
    scalar first seen later (the evaluation's, the imitation warm start's) becomes a new
    last column, and the file is rewritten atomically with the union of the columns
    (earlier rows get empty cells): columns never move or disappear, so a reader by
    name (:class:`csv.DictReader`, ``pandas.read_csv``) reads every row alike.

    Rows: scalars logged at the same step merge into one row until a name repeats, so
    an iteration's evaluation and update share a row. A row is on disk once it is logged
    (appended, or the file rewritten atomically when a row or the columns change); a
    kill can tear only the last line, which a resume drops
    (:func:`~rtaw_marl.training.checkpoints.trim_csv_logs`). An existing file (a resumed
    run's) is continued with its columns.

    Args:
        path: The CSV file.
    """

    def __init__(self, path: Path) -> None:
        self.path = Path(path)
        self.columns: list[str] = [FRAMES]
        self.rows: list[dict[str, str]] = []
        # What the last row may still take: (step, axis); None for rows read from disk.
        self._open: tuple[int, str | None] | None = None
        if self.path.is_file():
            self._read()

    def _read(self) -> None:
        with self.path.open(newline="") as fh:
            reader = csv.DictReader(fh)
            if reader.fieldnames and reader.fieldnames[0] == FRAMES:
                self.columns = list(reader.fieldnames)
                self.rows = [{k: v or "" for k, v in row.items() if k} for row in reader]

    def log(self, scalars: Mapping[str, float], step: int, axis: str | None = None) -> None:
        """Add ``scalars`` at ``step`` to the last row or as a new one, then write."""
        cells = {name: repr(float(value)) for name, value in scalars.items()}
        new = [name for name in cells if name not in self.columns]
        self.columns += new
        last = self.rows[-1] if self.rows else {}
        merge = self._open == (step, axis) and not any(last.get(name) for name in cells)
        if merge:
            last.update(cells)
        else:
            self.rows.append({FRAMES: str(int(step)), **cells})
            self._open = (step, axis)
        if new or merge or not self.path.is_file():
            atomic_write(self.path, self._write_all)
        else:
            with self.path.open("a", newline="") as fh:
                self._writer(fh).writerow(self.rows[-1])

    def _write_all(self, fh: Any) -> None:
        text = io.StringIO(newline="")
        writer = self._writer(text)
        writer.writeheader()
        writer.writerows(self.rows)
        fh.write(text.getvalue().encode())

    def _writer(self, fh: Any) -> csv.DictWriter:
        # "\n", as the rest of the run folder's text files (csv's default is "\r\n").
        return csv.DictWriter(fh, self.columns, restval="", lineterminator="\n")

    def close(self) -> None:
        """Nothing is buffered: every row is written when logged."""


class _TensorBoard:
    """TensorBoard event files through torchrl's logger (the ``tensorboard`` extra)."""

    def __init__(self, folder: Path) -> None:
        try:
            from torchrl.record.loggers.tensorboard import TensorboardLogger

            self._logger = TensorboardLogger(exp_name="train", log_dir=str(folder))
        except ImportError as exc:
            raise ConfigError(missing_extra("tensorboard", "TensorBoard", "tensorboard")) from exc

    def log(self, scalars: Mapping[str, float], step: int, axis: str | None) -> None:
        x = int(scalars[axis]) if axis else step
        for name, value in scalars.items():
            if name != axis:
                self._logger.log_scalar(name, float(value), step=x)

    def close(self) -> None:
        """torchrl's writer flushes on its own."""


def read_metrics(path: str | Path, column: str | None = None) -> list[dict[str, float]]:
    """The rows of a ``logger=csv`` file as ``{name: value}`` without the empty cells;
    with ``column``, only the rows that hold it.

    Example: the greedy TTD after each evaluation,
    ``[(r["frames"], r["eval/ttd"]) for r in read_metrics(path, "eval/ttd")]``.
    """
    with Path(path).open(newline="") as fh:
        rows = [{k: float(v) for k, v in row.items() if k and v} for row in csv.DictReader(fh)]
    return [row for row in rows if column is None or column in row]


#: ``logger=NAME`` -> the module it imports and the package's name (its extra is NAME).
_PACKAGES = {
    "tensorboard": ("tensorboard", "TensorBoard"),
    "mlflow": ("mlflow", "MLflow"),
    "wandb": ("wandb", "wandb"),
}


def check_installed(option: LoggerConfig | str) -> None:
    """Fail before a run starts when its logger's package is not installed.

    Raises:
        ConfigError: The package is missing; the message names the extra.
    """
    name = logger_option(option).name
    if name in _PACKAGES:
        module, package = _PACKAGES[name]
        try:
            importlib.import_module(module)
        except ImportError as exc:
            raise ConfigError(missing_extra(name, package, name)) from exc


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
