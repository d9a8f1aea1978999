"""Signals a long run turns into a clean stop: the first Ctrl-C (or SIGTERM) is a
request checked at a safe point, not an exception at an arbitrary bytecode."""

from __future__ import annotations

import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass

__all__ = ["StopRequest", "deferred_interrupt"]


@dataclass
class StopRequest:
    """Set by the first Ctrl-C inside :func:`deferred_interrupt`."""

    requested: bool = False


@contextmanager
def deferred_interrupt() -> Iterator[StopRequest]:
    """Turn the first Ctrl-C into a request the caller checks at a safe point.

    A ``KeyboardInterrupt`` raised at an arbitrary bytecode can leave torch or
    tensordict state half-changed (and then surface as an unrelated error); a training
    loop instead checks ``stop.requested`` between iterations and stops cleanly. A
    second Ctrl-C raises ``KeyboardInterrupt`` at once. Outside the main thread, or when
    SIGINT is ignored (a background job), nothing changes.

    Yields:
        The request flag.
    """
    stop = StopRequest()
    if threading.current_thread() is not threading.main_thread() or (
        signal.getsignal(signal.SIGINT) is signal.SIG_IGN
    ):
        yield stop
        return

    def request(signum: int, frame: object) -> None:
        if stop.requested:
            raise KeyboardInterrupt
        stop.requested = True

    previous = signal.signal(signal.SIGINT, request)
    try:
        yield stop
    finally:
        signal.signal(signal.SIGINT, previous)
