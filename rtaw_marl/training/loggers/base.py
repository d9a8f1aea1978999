"""What every logger backend is (:class:`Backend`), the one that writes nothing
(``logger=none``), and :class:`RunLogger`, what the training loop sees."""

from __future__ import annotations

import importlib
from abc import ABC, abstractmethod
from collections.abc import Mapping
from pathlib import Path
from typing import Any, ClassVar

from rtaw_marl.errors import ConfigError
from rtaw_marl.training.loggers.config import LoggerConfig

__all__ = ["Backend", "NoBackend", "RunLogger"]


class Backend(ABC):
    """Where a run's scalars go: one backend per ``logger`` option, registered under its
    :attr:`name` in :data:`rtaw_marl.training.loggers.LOGGERS`.

    Attributes:
        name: The ``logger=`` option it serves; also the extra that installs its package.
        requires: ``(module, package)``: the module it needs and the package's name in
            the "not installed" message; ``None``: nothing beyond the ``train`` extra.
    """

    name: ClassVar[str]
    requires: ClassVar[tuple[str, str] | None] = None

    @classmethod
    @abstractmethod
    def start(cls, option: LoggerConfig, run_dir: Path, config: Mapping[str, Any]) -> Backend:
        """The backend of one run.

        Args:
            option: The run's ``logger`` option (of this backend's :attr:`name`).
            run_dir: The run folder; backends write under ``run_dir/logs`` unless the
                option points elsewhere.
            config: The run's resolved config (plain dicts).
        """

    @abstractmethod
    def log(self, scalars: Mapping[str, float], step: int, axis: str | None) -> None:
        """Record ``scalars`` at ``step`` frames (``axis``: see :meth:`RunLogger.log`)."""

    @abstractmethod
    def close(self) -> None:
        """Flush and end the run."""

    @classmethod
    def not_installed(cls) -> ConfigError:
        """The one-line error for this backend's missing package (the extra installs
        beside an installed rtaw_marl, editable or not, as the CLI's others do)."""
        package = cls.requires[1] if cls.requires else cls.name
        install = f"pip install 'rtaw_marl[{cls.name}]'"
        return ConfigError(f"logger={cls.name} needs {package} (not installed): {install}")

    @classmethod  # noqa: B027 (an optional hook: most backends have no server)
    def check_reachable(cls, option: LoggerConfig) -> None:
        """Fail before a run starts when ``option`` names a server that does not answer
        (a backend with a server URI overrides this; by default there is none).

        Raises:
            ConfigError: The server does not answer (the message names the option).
        """

    @classmethod
    def check_installed(cls) -> None:
        """Raise :meth:`not_installed` when the module in :attr:`requires` is missing."""
        if cls.requires is not None:
            try:
                importlib.import_module(cls.requires[0])
            except ImportError as exc:
                raise cls.not_installed() from exc


class NoBackend(Backend):
    """``logger=none``: every scalar is dropped; nothing is written."""

    name = "none"

    @classmethod
    def start(cls, option: LoggerConfig, run_dir: Path, config: Mapping[str, Any]) -> NoBackend:
        return cls()

    def log(self, scalars: Mapping[str, float], step: int, axis: str | None) -> None:
        """Drop ``scalars``."""

    def close(self) -> None:
        """Nothing to end."""


class RunLogger:
    """A run's scalars, into its backend: ``log(scalars, step)`` with ``step`` the frames
    collected so far. Built by :func:`rtaw_marl.training.loggers.build_logger`.

    Args:
        backend: Where the scalars go.
    """

    def __init__(self, backend: Backend) -> None:
        self._backend: Backend | None = backend

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
        """End the MLflow or W&B run (the CSV file is complete already); once."""
        if self._backend is not None:
            self._backend.close()
            self._backend = None
