"""Run folders: checked before any work starts, and held by one process at a time.

Two runs must never write into one folder (their results, CSV rows and checkpoints
would interleave). Default folders are already unique (a timestamp plus the process
id); :func:`claim_folder` makes that a guarantee for every folder, including one the
user names: it takes an exclusive ``flock`` on ``<folder>/.rtaw.lock`` for the run's
lifetime (:func:`claim_file`: on ``.<name>.lock`` beside an output file). The kernel
drops the lock when the process dies, however it dies, so a killed run never leaves
its folder locked; a run that ends deletes its lock file, so none is left behind.

Before that, a path is checked as the later writes will need it, so a bad one costs
one line instead of a finished evaluation or a training run:

- its length: every name in it must fit the filesystem's ``NAME_MAX``, including the
  names written beside an output file (the lock ``.<name>.lock`` and
  :func:`~rtaw_marl.utils.atomic.atomic_write`'s ``.<name>.XXXXXXXX.tmp``), and the
  whole path ``PATH_MAX``, including what a run writes inside its folder
  (:data:`RUN_PATH_ROOM`);
- its free space: at least :data:`MIN_FREE_BYTES` (or what the caller says it needs);
- that a file can be created in it.

Running out of space later is one :class:`~rtaw_marl.errors.DiskFullError` line that
says what was kept (:func:`~rtaw_marl.utils.atomic.disk_full_guard`).
"""

from __future__ import annotations

import os
import shutil
import sys
import tempfile
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import TextIO

from rtaw_marl.errors import ConfigError, DiskFullError
from rtaw_marl.utils.atomic import disk_full_guard, temp_name
from rtaw_marl.utils.stale import remove_stale_temps

try:
    import fcntl
except ImportError:  # Windows: no advisory locks; folders stay unique by name only
    fcntl = None  # type: ignore[assignment]

__all__ = [
    "LOCK_NAME",
    "MIN_FREE_BYTES",
    "RUN_PATH_ROOM",
    "check_writable_dir",
    "check_writable_file",
    "claim_file",
    "claim_folder",
    "lock_name",
]

LOCK_NAME = ".rtaw.lock"

#: The free space a run's filesystem must have when it starts (32 MiB): room for a
#: results file, an episode journal, or a training run's checkpoints (about 100 KB
#: each for the paper's network) and logs. A caller that knows it needs more says so.
MIN_FREE_BYTES = 32 * 2**20

#: The length a run folder's path must leave for the paths written inside it (128
#: bytes). Training's deepest are W&B's offline files, ``logs/wandb/offline-run-<date>_
#: <time>-<id>/logs/debug-internal.log`` (71 bytes); TensorBoard's event files, which
#: carry the host name, can reach about 120.
RUN_PATH_ROOM = 128

# Used where the system does not report its limits (os.pathconf); Linux's values.
_NAME_MAX, _PATH_MAX = 255, 4096


def lock_name(name: str) -> str:
    """The lock file :func:`claim_file` takes beside an output file ``name``."""
    return f".{name}.lock"


def check_writable_dir(
    folder: str | Path,
    what: str = "output_dir",
    *,
    need: int = MIN_FREE_BYTES,
    room: int = RUN_PATH_ROOM,
) -> Path:
    """Create ``folder`` (and its parents) and check a run can write in it.

    Args:
        folder: The folder.
        what: The config key that named it, for the message.
        need: The free space (bytes) its filesystem must have.
        room: The length of the longest path (bytes, relative) the run writes inside.

    Raises:
        ConfigError: A name in the path is too long for its filesystem, or the path
            with what is written inside; it is a file or lies under one; its
            filesystem has less than ``need`` free; or it cannot be created or written.
    """
    folder = Path(folder)
    shown = f"{what}={_short(str(folder))}"
    _check_length(folder, shown, room=room)
    _check_space(folder, shown, need)
    problem = _unwritable(folder)
    if problem:
        raise ConfigError(f"{shown} cannot be written: {problem}")
    return folder


def check_writable_file(
    path: str | Path,
    what: str = "output",
    *,
    need: int = MIN_FREE_BYTES,
    siblings: Sequence[str] = (),
) -> Path:
    """Check ``path`` can be written (atomically, beside itself) before the work starts.

    Args:
        path: The output file.
        what: The config key that named it, for the message.
        need: The free space (bytes) its filesystem must have.
        siblings: Names of other files the run writes beside it (e.g. an episode
            journal); their length is checked too.

    Raises:
        ConfigError: A name in the path is too long for its filesystem, including the
            temporary and lock files written beside it, or the whole path is; it is a
            folder; its filesystem has less than ``need`` free; or its folder cannot be
            created or written.
    """
    path = Path(path)
    shown = f"{what}={_short(str(path))}"
    _check_length(path.parent, shown, file=path.name, siblings=siblings)
    if os.path.isdir(path):
        raise ConfigError(f"{what}={path} is a folder; name a file, e.g. {path / 'results.json'}")
    _check_space(path.parent, shown, need)
    problem = _unwritable(path.parent)
    if problem:
        raise ConfigError(f"{shown} cannot be written: {problem}")
    return path


# --------------------------------------------------------------------------- checks
def _check_length(
    folder: Path, shown: str, *, room: int = 0, file: str | None = None,
    siblings: Sequence[str] = (),
) -> None:  # fmt: skip
    """Refuse ``folder`` when one of its names is too long for its filesystem, or
    ``file`` (created in it), or a file written beside ``file`` (its temporary file, its
    lock, ``siblings``), or the full path with what is written in it (``room``)."""
    full = Path(os.path.abspath(folder))
    name_max, path_max = _limits(_existing(full))
    for part in full.parts[1:]:
        if _bytes(part) > name_max:
            raise ConfigError(
                f"{shown}: the folder name {_short(part, 24)!r} is {_size(part)}; names on "
                f"its filesystem are at most {name_max} bytes"
            )
    names = [] if file is None else [file, temp_name(file), lock_name(file), *siblings]
    if file is not None:
        _check_file_name(file, names, shown, name_max)
    extra = max([room, *(1 + _bytes(n) for n in names)])
    total = _bytes(str(full)) + extra
    # PATH_MAX counts the terminating NUL byte.
    if total >= path_max:
        where = "inside it" if file is None else "beside it"
        raise ConfigError(
            f"{shown}: the path is too long ({total:,} bytes as a full path, with the "
            f"files written {where}); this system allows at most {path_max - 1:,} bytes"
        )


def _check_file_name(file: str, names: Sequence[str], shown: str, name_max: int) -> None:
    """Refuse ``file`` when it, or a name written beside it, exceeds ``name_max``."""
    if _bytes(file) > name_max:
        raise ConfigError(
            f"{shown}: the file name is {_size(file)}; names on its filesystem are at most "
            f"{name_max} bytes"
        )
    longest = max(names, key=_bytes)
    over = _bytes(longest) - name_max
    if over > 0:
        raise ConfigError(
            f"{shown}: the file name ({_size(file)}) is too long for the files written "
            f"beside it: {_short(longest, 24)!r} is {_bytes(longest)} bytes and names on "
            f"its filesystem are at most {name_max}; use a name of at most "
            f"{_bytes(file) - over} bytes"
        )


def _check_space(folder: Path, shown: str, need: int) -> None:
    """Refuse a folder whose filesystem has less than ``need`` bytes free."""
    if need <= 0:
        return
    try:
        usage = shutil.disk_usage(_existing(Path(os.path.abspath(folder))))
    except OSError:  # no answer: the write probe decides
        return
    # A size of 0 is a filesystem without one (/proc, some FUSE mounts): the write
    # probe decides there too.
    free = usage.free if usage.total > 0 else need
    if free < need:
        raise ConfigError(
            f"{shown}: only {_mib(free)} free on its filesystem; a run needs at least {_mib(need)}"
        )


def _unwritable(folder: Path) -> str | None:
    """Why no file can be created in ``folder`` (created if missing), or ``None``."""
    for parent in (folder, *folder.parents):
        if os.path.lexists(parent):
            if not os.path.isdir(parent):
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


def _existing(path: Path) -> Path:
    """``path`` or its nearest folder that exists (where its limits and space are)."""
    for parent in (path, *path.parents):
        if os.path.isdir(parent):  # os.path: False, not an error, for a too-long path
            return parent
    return Path(path.anchor or ".")


def _limits(folder: Path) -> tuple[int, int]:
    """``(NAME_MAX, PATH_MAX)`` of the filesystem holding ``folder``, in bytes."""
    limits = []
    for key, fallback in (("PC_NAME_MAX", _NAME_MAX), ("PC_PATH_MAX", _PATH_MAX)):
        try:
            value = os.pathconf(folder, key)
        except (AttributeError, OSError, ValueError):  # no pathconf (Windows) or no answer
            value = fallback
        limits.append(value if value > 0 else fallback)
    return limits[0], limits[1]


def _bytes(text: str) -> int:
    """The length the kernel measures: bytes of the filesystem encoding."""
    return len(os.fsencode(text))


def _size(text: str) -> str:
    """``"300 characters"``, or ``"310 bytes"`` where they differ (non-ASCII)."""
    n = _bytes(text)
    return f"{n} characters" if n == len(text) else f"{n} bytes"


def _short(text: str, keep: int = 60) -> str:
    """``text``, its middle elided when it is over ``2 * keep`` characters (a path of
    thousands of characters would fill the terminal)."""
    if len(text) <= 2 * keep + 3:
        return text
    return f"{text[:keep]}...{text[-keep:]}"


def _mib(n: int) -> str:
    """``"1.2 MiB"``; ``"32 MiB"`` for a whole number."""
    return f"{n >> 20} MiB" if n % 2**20 == 0 else f"{n / 2**20:.1f} MiB"


# --------------------------------------------------------------------------- claims
@contextmanager
def claim_folder(
    folder: str | Path,
    what: str = "output_dir",
    *,
    need: int = MIN_FREE_BYTES,
    room: int = RUN_PATH_ROOM,
) -> Iterator[Path]:
    """Hold ``folder`` for this run: another process claiming it fails at once.

    Args:
        folder: The run folder (created if missing).
        what: The config key that named it, for the message.
        need: The free space (bytes) its filesystem must have (:func:`check_writable_dir`).
        room: The longest path the run writes inside it (:func:`check_writable_dir`).

    Yields:
        The folder.

    Raises:
        ConfigError: Another running process holds the folder, or a check of
            :func:`check_writable_dir` fails.
        DiskFullError: The disk filled up while taking the lock.
    """
    folder = check_writable_dir(folder, what, need=need, room=room)
    with _hold(folder / LOCK_NAME, f"{what}={_short(str(folder))}"):
        yield folder


@contextmanager
def claim_file(
    path: str | Path,
    what: str = "output",
    *,
    need: int = MIN_FREE_BYTES,
    siblings: Sequence[str] = (),
    note: Callable[[str], None] | None = None,
) -> Iterator[Path]:
    """Hold the output file ``path`` (and what is written beside it) for this run.

    The lock is ``.<name>.lock`` beside it, so runs writing other files of the same
    folder do not block each other. ``need`` and ``siblings`` are passed to
    :func:`check_writable_file`. Once held, the temporaries a killed earlier write of
    ``path`` or a sibling left (:func:`~rtaw_marl.utils.stale.remove_stale_temps`) are
    removed: the claim guarantees no live process writes them.

    Args:
        path: The output file.
        what: The config key that named it, for messages.
        need: The free space (bytes) its filesystem must have.
        siblings: Names of other files the run writes beside it.
        note: Told which leftovers were removed (default: a ``note:`` line on stderr).

    Raises:
        ConfigError: Another running process writes ``path``, or a check of
            :func:`check_writable_file` fails.
        DiskFullError: The disk filled up while taking the lock.
    """
    path = check_writable_file(path, what, need=need, siblings=siblings)
    with _hold(path.with_name(lock_name(path.name)), f"{what}={_short(str(path))}"):
        removed = [
            p for name in (path.name, *siblings) for p in remove_stale_temps(path.with_name(name))
        ]
        if removed:
            left = ", ".join(p.name for p in removed)
            (note or _note)(f"removed what a killed earlier write of {path.name} left: {left}")
        yield path


def _note(line: str) -> None:
    print(f"note: {line}", file=sys.stderr)


@contextmanager
def _hold(lock_path: Path, name: str) -> Iterator[None]:
    """Hold ``lock_path`` (``flock``) for the body; the lock file is gone afterwards.

    The holder deletes the file before it unlocks, so a process that opened it in the
    meantime may lock a file no longer on disk: after locking, the inode on disk must be
    the one locked, else it tries again on the new file.
    """
    if fcntl is None:
        yield
        return
    kept = f"the run did not start and {name} was left as it was"
    for _ in range(_LOCK_TRIES):
        lock = _open_lock(lock_path, name, kept)
        try:
            fcntl.flock(lock.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            lock.seek(0)
            holder = lock.read().strip() or "?"
            lock.close()
            raise ConfigError(
                f"{name} is in use by another running process (pid {holder}); choose another one"
            ) from None
        if _same_file(lock, lock_path):
            break
        lock.close()  # its holder deleted it after we opened it: lock the new one
    else:
        raise ConfigError(f"{name}: could not take its lock file {lock_path}")
    with lock:
        # The guard covers the pid write only: an error of the run itself (the body)
        # must pass through unrenamed.
        with disk_full_guard(lock_path, kept):
            lock.seek(0)
            lock.truncate()
            lock.write(str(os.getpid()))
            lock.flush()
        try:
            yield
        finally:
            lock_path.unlink(missing_ok=True)  # still locked: nobody holds it meanwhile
            fcntl.flock(lock.fileno(), fcntl.LOCK_UN)


#: Attempts at locking a lock file that its holder deletes meanwhile.
_LOCK_TRIES = 100


def _same_file(lock: TextIO, lock_path: Path) -> bool:
    """Whether the open ``lock`` is the file at ``lock_path`` now (not one deleted)."""
    try:
        return os.stat(lock_path).st_ino == os.fstat(lock.fileno()).st_ino
    except FileNotFoundError:
        return False


def _open_lock(lock_path: Path, name: str, kept: str) -> TextIO:
    """The lock file, opened for appending; a full disk is a :class:`DiskFullError`,
    another failure (read-only filesystem, a lock file of another user) one line."""
    try:
        with disk_full_guard(lock_path, kept):
            return open(lock_path, "a+")
    except OSError as exc:
        if isinstance(exc, DiskFullError):
            raise
        raise ConfigError(
            f"{name} cannot be written: {exc.strerror or type(exc).__name__} ({lock_path})"
        ) from None
