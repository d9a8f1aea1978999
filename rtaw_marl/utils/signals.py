"""Signals a long run turns into a clean stop.

SIGINT (Ctrl-C) and SIGTERM (what schedulers, ``kill`` and ``timeout`` send) mean the
same here: stop, keep what is done, print one line, exit ``128 + signal`` (130 and 143).
:func:`terminate_as_interrupt` makes SIGTERM raise :class:`Interrupted` as Ctrl-C raises
``KeyboardInterrupt``; :func:`deferred_interrupt` turns the first of either signal into a
request a training loop checks at a safe point.
"""

from __future__ import annotations

import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass

__all__ = [
    "STOP_SIGNALS",
    "Interrupted",
    "StopRequest",
    "deferred_interrupt",
    "signals_held",
    "terminate_as_interrupt",
]

#: The signals that stop a run cleanly.
STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM)


class Interrupted(KeyboardInterrupt):
    """A run stopped by a signal; ``str()`` is the one line for the user.

    Args:
        message: What was kept and how to continue (may be empty).
        signum: The signal that stopped it.
    """

    def __init__(self, message: str = "", signum: int = signal.SIGINT) -> None:
        super().__init__(message)
        self.signum = int(signum)

    @property
    def exit_status(self) -> int:
        """``128 + signum``, the shell's convention (130 for SIGINT, 143 for SIGTERM)."""
        return 128 + self.signum


def _main_thread() -> bool:
    return threading.current_thread() is threading.main_thread()


@contextmanager
def terminate_as_interrupt() -> Iterator[None]:
    """Within the block, SIGTERM raises :class:`Interrupted` (``signum=SIGTERM``) as
    Ctrl-C raises ``KeyboardInterrupt``, so ``finally`` blocks and journals close as on
    Ctrl-C instead of the process dying mid-write. Outside the main thread, or when
    SIGTERM is ignored, nothing changes."""
    if not _main_thread() or signal.getsignal(signal.SIGTERM) is signal.SIG_IGN:
        yield
        return

    def terminate(signum: int, frame: object) -> None:
        raise Interrupted(signum=signum)

    previous = signal.signal(signal.SIGTERM, terminate)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


@dataclass
class StopRequest:
    """Set by the first SIGINT or SIGTERM inside :func:`deferred_interrupt`."""

    requested: bool = False
    #: The signal that requested the stop (``None`` until one does).
    signum: int | None = None


@contextmanager
def deferred_interrupt() -> Iterator[StopRequest]:
    """Turn the first Ctrl-C or SIGTERM into a request the caller checks at a safe point.

    A ``KeyboardInterrupt`` raised at an arbitrary bytecode can leave torch or
    tensordict state half-changed (and then surface as an unrelated error); a training
    loop instead checks ``stop.requested`` between iterations and stops cleanly. A
    second signal raises :class:`Interrupted` at once. Outside the main thread nothing
    changes; a signal the process ignores (SIGINT in a background job) stays ignored.

    Yields:
        The request flag.
    """
    stop = StopRequest()
    if not _main_thread():
        yield stop
        return

    def request(signum: int, frame: object) -> None:
        if stop.requested:
            raise Interrupted(signum=signum)
        stop.requested, stop.signum = True, signum

    previous = {}
    for signum in STOP_SIGNALS:
        if signal.getsignal(signum) is not signal.SIG_IGN:
            previous[signum] = signal.signal(signum, request)
    try:
        yield stop
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, handler)


@contextmanager
def signals_held() -> Iterator[None]:
    """SIGINT and SIGTERM that arrive within the block are handled right after it.

    For a few lines that must happen together or not at all, such as a journal line
    written and counted, or a set of files renamed in. The Python-level handlers are
    swapped for one that notes the signal, and the signal is raised again once they are
    back. Not a signal mask: a mask holds the calling thread's signals only, and the
    kernel hands a process's signal to any thread that does not block it (one of
    numpy's, a tracker's, pytest's), whose C handler then has the Python handler run in
    the main thread inside the block all the same. Outside the main thread, or for a
    signal that is ignored, nothing changes.
    """
    if not _main_thread():
        yield
        return
    pending: list[int] = []
    previous = {}
    for signum in STOP_SIGNALS:
        handler = signal.getsignal(signum)
        # None: a handler installed outside Python, which cannot be restored; leave it.
        if handler is not signal.SIG_IGN and handler is not None:
            previous[signum] = signal.signal(signum, lambda s, _: pending.append(s))
    try:
        yield
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, handler)
        for signum in dict.fromkeys(pending):
            signal.raise_signal(signum)  # now handled as it would have been
