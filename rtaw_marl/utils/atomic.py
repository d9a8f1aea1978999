"""Atomic file writes: a crash at any moment leaves the old file or the complete new one."""

from __future__ import annotations

import errno
import os
import tempfile
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import BinaryIO

from rtaw_marl.errors import DiskFullError

__all__ = ["DISK_FULL", "atomic_write", "disk_full_guard", "temp_name"]

#: The errnos of a write that found no room: the disk is full, or the user's quota is.
DISK_FULL = frozenset({errno.ENOSPC, errno.EDQUOT})

#: How many random characters :func:`tempfile.mkstemp` puts in a name.
_RANDOM_CHARS = 8


def temp_name(name: str) -> str:
    """The shape of :func:`atomic_write`'s temporary file for ``name`` (the ``X`` are
    random): ``.<name>.XXXXXXXX.tmp``. Its length is what a path check must allow for.
    """
    return f".{name}.{'X' * _RANDOM_CHARS}.tmp"


@contextmanager
def disk_full_guard(path: str | Path, kept: str) -> Iterator[None]:
    """Turn a full disk (or quota) while writing ``path`` into one :class:`DiskFullError`
    line that says what was kept; other OS errors pass through.

    Args:
        path: The file being written (named in the message).
        kept: What is intact on disk, e.g. ``"the previous last.pt is kept"``.
    """
    try:
        yield
    except OSError as exc:
        if exc.errno not in DISK_FULL or isinstance(exc, DiskFullError):
            raise
        raise DiskFullError(
            f"no space left on the device writing {path} ({exc.strerror}); {kept}"
        ) from exc


def atomic_write(path: str | Path, write: Callable[[BinaryIO], None]) -> Path:
    """Call ``write`` on a temporary file beside ``path``, fsync it, then rename it over ``path``.

    Args:
        path: The target file (parent folders are created).
        write: Writes the content to the binary file object it is given.

    Returns:
        ``path``.

    Raises:
        DiskFullError: The disk or quota is full; the previous ``path`` (if any) is
            intact and no temporary file is left.
    """
    path = Path(path)
    kept = f"the previous {path.name} is kept" if path.exists() else f"no {path.name} was written"
    with disk_full_guard(path, kept):
        return _atomic_write(path, write)


def _atomic_write(path: Path, write: Callable[[BinaryIO], None]) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    # Named as temp_name() says; the leading dot hides it, and a killed write's
    # leftover is recognisable (.last.pt.*.tmp).
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    # mkstemp creates the file 0600; give the result the usual permissions instead.
    umask = os.umask(0)
    os.umask(umask)
    os.chmod(tmp, 0o666 & ~umask)
    try:
        with os.fdopen(fd, "wb") as fh:
            write(fh)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path
