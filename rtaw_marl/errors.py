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
        prefix: Written before each suggestion (``"sim."``, ``"navigator="``), so the
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


#: Extra (``pip install 'rtaw_marl[EXTRA]'``) -> the top-level modules it installs that
#: rtaw_marl imports (pyproject.toml; PyYAML comes with omegaconf). The one table behind
#: every "needs the ... extra" message: the console scripts' and the Python API's.
EXTRAS: dict[str, tuple[str, ...]] = {
    "cli": ("hydra", "omegaconf", "yaml", "tqdm", "matplotlib", "PIL"),
    "train": ("torch", "tensordict", "torchrl"),
    "export": ("onnx", "onnxscript", "onnxruntime"),
    "lorr": ("pybind11",),
}
#: Extra -> its name in messages ("needs the training extra").
EXTRA_NAMES: dict[str, str] = {
    "cli": "command-line",
    "train": "training",
    "export": "export",
    "lorr": "LoRR",
}
#: Extra -> the extras it installs too (``train = ["rtaw_marl[cli]", ...]``).
_INCLUDES: dict[str, tuple[str, ...]] = {
    "cli": (),
    "train": ("cli",),
    "export": ("train",),
    "lorr": ("cli",),
}


def extra_modules(extra: str) -> tuple[str, ...]:
    """The top-level modules ``pip install 'rtaw_marl[extra]'`` provides: those of the
    extras it includes first (``train``: the ``cli`` extra's, then torch, tensordict,
    torchrl)."""
    included = tuple(m for other in _INCLUDES[extra] for m in extra_modules(other))
    return included + EXTRAS[extra]


def extra_message(what: str, extra: str, module: str) -> str:
    """The one line saying that ``what`` needs ``extra``, e.g. ``"load_policy needs the
    training extra ('torch' is not installed): pip install 'rtaw_marl[train]'"``.

    Args:
        what: The command or Python name that cannot run (``"rtaw-train"``,
            ``"load_policy"``, ``"rtaw_marl.envs.torchrl"``).
        extra: A key of :data:`EXTRAS`.
        module: The missing module.
    """
    return (
        f"{what} needs the {EXTRA_NAMES[extra]} extra ({module!r} is not installed): "
        f"pip install 'rtaw_marl[{extra}]'"
    )


class MissingExtraError(RtawError, ModuleNotFoundError):
    """A part of the Python API needs an extra that is not installed; the message names
    the extra and the ``pip install`` line (:func:`extra_message`).

    Also a ``ModuleNotFoundError`` whose ``name`` is the missing module, so code that
    catches ``ImportError`` (or reads ``exc.name``) works as with the raw error.
    """

    def __init__(self, message: str, *, extra: str = "", name: str | None = None) -> None:
        # Keyword arguments with defaults: pickle rebuilds an exception from its message
        # alone (then restores name and extra), e.g. one raised in an evaluation worker.
        super().__init__(message, name=name)
        self.extra = extra


def missing_extra(exc: ModuleNotFoundError, what: str, extra: str) -> ModuleNotFoundError:
    """The error to raise for ``exc``, raised while importing what ``what`` needs.

    The import guard of a module that needs an extra::

        try:
            import torch
        except ModuleNotFoundError as exc:
            raise missing_extra(exc, __name__, "train") from None

    Args:
        exc: The import's error.
        what: The name the message gives (a module's ``__name__``, a function's name).
        extra: The extra ``what`` needs (a key of :data:`EXTRAS`).

    Returns:
        A :class:`MissingExtraError` when the missing module is one ``extra`` installs;
        else ``exc`` itself: a module missing from an installed extra is a broken
        install, whose own error says more.
    """
    root = (exc.name or "").partition(".")[0]
    if root not in extra_modules(extra):
        return exc
    return MissingExtraError(extra_message(what, extra, root), extra=extra, name=root)
