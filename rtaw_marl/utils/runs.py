"""Run folders: checked before any work starts, and held by one process at a time.

Two runs must never write into one folder (their results, CSV rows and checkpoints
would interleave). Default folders are already unique (a timestamp plus the process
id); :func:`claim_folder` makes that a guarantee for every folder, including one the
user names: it takes an exclusive ``flock`` on ``<folder>/.rtaw.lock`` for the run's
lifetime (:func:`claim_file`: on ``.<name>.lock`` beside an output file). The kernel
drops the lock when the process dies, however it dies, so a killed run never leaves
its folder locked.
"""

from __future__ import annotations

import os
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from rtaw_marl.errors import ConfigError

try:
    import fcntl
except ImportError:  # Windows: no advisory locks; folders stay unique by name only
    fcntl = None  # type: ignore[assignment]

__all__ = [
    "LOCK_NAME",
    "check_writable_dir",
    "check_writable_file",
    "claim_file",
    "claim_folder",
]

LOCK_NAME = ".rtaw.lock"


def check_writable_dir(folder: str | Path, what: str = "output_dir") -> Path:
    """Create ``folder`` (and its parents) and check a file can be written in it.

    Args:
        folder: The folder.
        what: The config key that named it, for the message.

    Raises:
        ConfigError: It is a file, lies under a file, or cannot be created or written.
    """
    folder = Path(folder)
    problem = _unwritable(folder)
    if problem:
        raise ConfigError(f"{what}={folder} cannot be written: {problem}")
    return folder


def check_writable_file(path: str | Path, what: str = "output") -> Path:
    """Check ``path`` can be written (atomically, beside itself) before the work starts.

    Raises:
        ConfigError: It is a folder, or its folder cannot be created or written.
    """
    path = Path(path)
    if path.is_dir():
        raise ConfigError(f"{what}={path} is a folder; name a file, e.g. {path / 'results.json'}")
    problem = _unwritable(path.parent)
    if problem:
        raise ConfigError(f"{what}={path} cannot be written: {problem}")
    return path


def _unwritable(folder: Path) -> str | None:
    """Why no file can be created in ``folder`` (created if missing), or ``None``."""
    for parent in (folder, *folder.parents):
        if parent.exists():
            if not parent.is_dir():
                return f"{parent} is a file, not a folder"
            break
    try:
        folder.mkdir(parents=True, exist_ok=True)
        fd, probe = tempfile.mkstemp(prefix=".rtaw-probe-", dir=folder)
        os.close(fd)
        os.unlink(probe)
    except OSError as exc:
        return f"{exc.strerror or type(exc).__name__} ({folder})"
    return None


@contextmanager
def claim_folder(folder: str | Path, what: str = "output_dir") -> Iterator[Path]:
    """Hold ``folder`` for this run: another process claiming it fails at once.

    Args:
        folder: The run folder (created if missing).
        what: The config key that named it, for the message.

    Yields:
        The folder.

    Raises:
        ConfigError: Another running process holds the folder, or it cannot be written.
    """
    folder = check_writable_dir(folder, what)
    with _hold(folder / LOCK_NAME, f"{what}={folder}"):
        yield folder


@contextmanager
def claim_file(path: str | Path, what: str = "output") -> Iterator[Path]:
    """Hold the output file ``path`` (and what is written beside it) for this run.

    The lock is ``.<name>.lock`` beside it, so runs writing other files of the same
    folder do not block each other.

    Raises:
        ConfigError: Another running process writes ``path``, or it cannot be written.
    """
    path = check_writable_file(path, what)
    with _hold(path.with_name(f".{path.name}.lock"), f"{what}={path}"):
        yield path


@contextmanager
def _hold(lock_path: Path, name: str) -> Iterator[None]:
    if fcntl is None:
        yield
        return
    with open(lock_path, "a+") as lock:
        try:
            fcntl.flock(lock.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            lock.seek(0)
            holder = lock.read().strip() or "?"
            raise ConfigError(
                f"{name} is in use by another running process (pid {holder}); choose another one"
            ) from None
        lock.seek(0)
        lock.truncate()
        lock.write(str(os.getpid()))
        lock.flush()
        try:
            yield
        finally:
            fcntl.flock(lock.fileno(), fcntl.LOCK_UN)
