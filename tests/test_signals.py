"""Signals held for a few lines: handled right after the block, whatever thread the
kernel hands them to."""

from __future__ import annotations

import os
import signal
import sys
import threading

import pytest

from rtaw_marl.utils.signals import signals_held

pytestmark = [
    pytest.mark.unit,
    pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals"),
]


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_a_signal_inside_the_block_is_handled_after_it_with_other_threads(signum: int) -> None:
    """With another thread running (it does not block the signal), a signal mask on the
    main thread alone let the handler run inside the block; the block must hold it."""
    stop = threading.Event()
    other = threading.Thread(target=stop.wait, daemon=True)
    other.start()
    seen: list[str] = []
    previous = signal.signal(signum, lambda s, _: seen.append("handled"))
    try:
        with signals_held():
            os.kill(os.getpid(), signum)
            for _ in range(100_000):  # time for any delivery to happen
                pass
            seen.append("block ends")
        assert seen == ["block ends", "handled"]
    finally:
        signal.signal(signum, previous)
        stop.set()
        other.join()


def test_the_handlers_are_back_after_the_block() -> None:
    before = signal.getsignal(signal.SIGTERM)
    with signals_held():
        assert signal.getsignal(signal.SIGTERM) is not before
    assert signal.getsignal(signal.SIGTERM) is before
