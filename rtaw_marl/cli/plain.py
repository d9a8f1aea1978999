"""What the argparse commands (``rtaw-zoo``, ``rtaw-results``, ``rtaw-export``) share
with the Hydra ones: one ``error: ...`` line and exit status 2 for bad input, status 1
for a run that failed, one ``interrupted`` line and 130 for Ctrl-C, 143 for SIGTERM."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable
from typing import NoReturn

from rtaw_marl.errors import RtawError
from rtaw_marl.utils.signals import Interrupted, terminate_as_interrupt

__all__ = ["OneLineParser", "exit_after"]


class OneLineParser(argparse.ArgumentParser):
    """argparse with one-line errors (``error: ...``, exit status 2)."""

    def error(self, message: str) -> NoReturn:
        print(f"error: {message}", file=sys.stderr)
        sys.exit(2)


def _first_line(exc: BaseException) -> str:
    if isinstance(exc, OSError) and not isinstance(exc, RtawError):
        where = f": {exc.filename}" if exc.filename else ""
        return f"{exc.strerror or exc}{where}".splitlines()[0]
    return (str(exc).splitlines() or [type(exc).__name__])[0]


def exit_after(
    run: Callable[[list[str] | None], int],
    argv: list[str] | None,
    failures: tuple[type[BaseException], ...] = (),
    describe: Callable[[BaseException], str] = _first_line,
) -> NoReturn:
    """Run a command and exit with its status.

    Args:
        run: The command; returns its exit status.
        argv: Its arguments (``None``: ``sys.argv[1:]``).
        failures: Exceptions meaning the command ran and failed (exit status 1).
        describe: The one line printed for one of ``failures``.
    """
    try:
        with terminate_as_interrupt():
            status = run(argv)
    except failures as exc:
        print(f"error: {describe(exc)}", file=sys.stderr)
        sys.exit(1)
    except (RtawError, OSError) as exc:
        print(f"error: {_first_line(exc)}", file=sys.stderr)
        sys.exit(2)
    except KeyboardInterrupt as exc:
        print(f"interrupted{': ' + str(exc) if str(exc) else ''}", file=sys.stderr)
        sys.exit(exc.exit_status if isinstance(exc, Interrupted) else 130)
    sys.exit(status)
