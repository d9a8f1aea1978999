"""Exceptions raised for bad input.

Every error a user can cause (a bad config value, a missing or malformed file, an
invalid action) derives from :class:`RtawError`, so command-line entry points can
print its one-line message and exit non-zero without a traceback.
"""

from __future__ import annotations

import difflib
from collections.abc import Iterable, Mapping
from typing import TypeVar

T = TypeVar("T")


class RtawError(Exception):
    """Base class of all user-facing errors of rtaw_marl."""


class ConfigError(RtawError, ValueError):
    """A configuration value is missing, of the wrong type or out of range."""


class LayoutError(ConfigError):
    """A layout file is missing or malformed, or a cell is blocked or unreachable."""


class TaskFileError(ConfigError):
    """A task file is missing or malformed, or a task lies on a blocked cell."""


class InvalidActionError(RtawError, ValueError):
    """An action names a queue slot that is out of range or empty."""


def close_names(name: str, choices: Iterable[str], n: int = 3) -> list[str]:
    """The valid names closest to a misspelt ``name``, best first (none when none is close).

    Case is ignored (``row=c`` finds ``C``); otherwise :func:`difflib.get_close_matches`
    ranks them, with its default cutoff (0.6 similarity).
    """
    by_lower: dict[str, str] = {}
    for choice in choices:
        by_lower.setdefault(choice.lower(), choice)
    wanted = name.lower()
    if wanted in by_lower:
        return [by_lower[wanted]]
    close = difflib.get_close_matches(wanted, list(by_lower), n=n)
    # Equally close names in alphabetical order (difflib puts ties in reverse).
    close.sort(key=lambda m: (-difflib.SequenceMatcher(None, wanted, m).ratio(), m))
    return [by_lower[m] for m in close]


def did_you_mean(name: str, choices: Iterable[str], prefix: str = "") -> str:
    """``"; did you mean 'x'?"`` naming the choices closest to ``name``, else ``""``.

    The one place every "unknown name" message gets its suggestion (registries, config
    keys, config group options), appended after the list of valid names.

    Args:
        name: What the user typed.
        choices: The valid names.
        prefix: Written before each suggestion (``"env."``, ``"navigator="``), so the
            suggestion is what to type.
    """
    close = [repr(f"{prefix}{c}") for c in close_names(name, choices)]
    if not close:
        return ""
    spelled = close[0] if len(close) == 1 else f"{', '.join(close[:-1])} or {close[-1]}"
    return f"; did you mean {spelled}?"


def unknown_name(kind: str, name: str, available: list[str] | tuple[str, ...]) -> ConfigError:
    """Build the error for an unknown registry name, listing what exists and suggesting
    the closest names (:func:`did_you_mean`).

    Args:
        kind: What was looked up, e.g. ``"navigator"``.
        name: The name that was not found.
        available: The names that exist.

    Returns:
        A :class:`ConfigError` to raise.
    """
    listing = ", ".join(sorted(available))
    return ConfigError(
        f"unknown {kind} {name!r}; available: {listing}{did_you_mean(name, available)}"
    )


def lookup(registry: Mapping[str, T], kind: str, name: str) -> T:
    """``registry[name]``, or the :func:`unknown_name` error listing what exists.

    Raises:
        ConfigError: ``name`` is not registered.
    """
    try:
        return registry[name]
    except KeyError:
        raise unknown_name(kind, name, list(registry)) from None


class DiskFullError(RtawError, OSError):
    """A write ran out of disk space (or quota); the message names the file and what
    was kept (atomic writes leave the previous file whole)."""


class PlanningError(RtawError, RuntimeError):
    """A collision-aware navigator could not complete the tasks it was given."""


class PlanningTimeout(PlanningError):
    """One planning call ran past the navigator's ``time_limit``."""


class ScheduleError(RtawError, AssertionError):
    """An executed schedule breaks a rule: a conflict, an illegal move, a task not served."""


class EnvUsageError(RtawError, RuntimeError):
    """An env's Python API was used out of order (after ``close()``) or given an argument
    it does not take; the message says what to call or pass instead."""


class ResetNeededError(EnvUsageError, AttributeError):
    """An env was used before its first ``reset()``. Also an ``AttributeError``, what
    PettingZoo raises for ``agents`` or ``agent_selection`` before reset, so ``hasattr``
    still answers ``False``."""


class UnknownAgentError(EnvUsageError, KeyError):
    """An agent name outside the env's ``possible_agents``. Also a ``KeyError``, what a
    lookup in PettingZoo's per-agent dicts raises."""

    def __str__(self) -> str:
        # KeyError's str() is the repr of its argument; keep the message as written.
        return str(self.args[0]) if self.args else ""


def usage_error(call: str, closed: bool = False) -> EnvUsageError:
    """Build the error for ``call`` on an env that is not live.

    Args:
        call: The call, as the message names it, e.g. ``"env.step()"``.
        closed: Whether the env was closed (else it was never reset).

    Returns:
        An :class:`EnvUsageError` (a :class:`ResetNeededError` before the first reset) to
        raise.
    """
    if closed:
        return EnvUsageError(f"{call} after close(): this env is closed; make a new one")
    return ResetNeededError(f"{call} before reset(): call env.reset() first")
