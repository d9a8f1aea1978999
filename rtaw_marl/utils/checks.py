"""Checks every typed config shares: values match their fields' types, and ranges.

Hydra's typed composition already refuses most wrong types on the command line, but a
config built in Python (``SimConfig(num_robots=2.5)``, ``EvalConfig(progress="off")``,
``SimSpec.of(layout={"name": "open", "width": 10.7})``) reaches the dataclasses
unchecked, and a float field takes ``nan``/``inf`` from either route. So each config
dataclass calls :func:`check_fields` first in ``__post_init__``; its own rules (ranges,
choices) follow, most through :func:`at_least` and :func:`check_number`.

The rules by annotation: ``bool`` takes only a real boolean (``"off"`` is truthy in
Python, so a string would silently mean true); ``int`` takes only an integer, not
``10.7`` nor ``10.0`` (nothing is silently truncated); ``float`` takes a finite number;
``str`` a string; ``list[X]`` a list (or tuple) whose items are checked as ``X``;
``X | None`` also ``None``; ``Any`` anything; a class, its instances.
"""

from __future__ import annotations

import dataclasses
import math
import types
import typing
from functools import cache
from typing import Any

import numpy as np

from rtaw_marl.errors import ConfigError

__all__ = ["at_least", "check_fields", "check_number", "check_value"]


def check_fields(obj: object, prefix: str = "") -> None:
    """Check every field of the dataclass ``obj`` against its annotation.

    Args:
        obj: A dataclass instance.
        prefix: How its keys are named in messages, e.g. ``"sim."``.

    Raises:
        ConfigError: A value does not fit its field's type; the message names the key
            (``sim.robot_starts[0][1]``) and the value.
    """
    hints = _hints(type(obj))
    for f in dataclasses.fields(obj):  # type: ignore[arg-type]
        check_value(f"{prefix}{f.name}", getattr(obj, f.name), hints.get(f.name, Any))


def check_value(key: str, value: object, hint: Any) -> None:
    """Check one ``value`` against the type ``hint`` (see the module's rules).

    Raises:
        ConfigError: It does not fit; the message names ``key``.
    """
    if hint is Any or isinstance(hint, typing.TypeVar):
        return
    origin = typing.get_origin(hint)
    if origin is typing.Union or origin is types.UnionType:
        _check_union(key, value, typing.get_args(hint))
    elif hint is bool:
        if not isinstance(value, (bool, np.bool_)):
            raise ConfigError(f"{key} must be true or false, got {value!r}")
    elif hint is int:
        if not _is_int(value):
            raise ConfigError(f"{key} must be an integer, got {value!r}")
    elif hint is float:
        check_number(key, value)
    elif hint is str:
        if not isinstance(value, str):
            raise ConfigError(f"{key} must be a string, got {value!r}")
    elif origin in (list, tuple) or hint in (list, tuple):
        _check_items(key, value, typing.get_args(hint))
    elif origin is dict or hint is dict:
        if not isinstance(value, dict):
            raise ConfigError(f"{key} must be a mapping, got {value!r}")
    elif isinstance(hint, type) and not isinstance(value, hint):
        raise ConfigError(f"{key} must be a {hint.__name__}, got {value!r}")


def check_number(
    key: str, value: object, *, minimum: float | None = None, above: float | None = None
) -> None:
    """Check that ``value`` is a finite real number, optionally ``>= minimum`` or
    ``> above``.

    Raises:
        ConfigError: It is not a number (a bool, a string), is ``nan``/``inf``, or is out
            of range.
    """
    if isinstance(value, (bool, np.bool_)) or not isinstance(
        value, (int, float, np.integer, np.floating)
    ):
        raise ConfigError(f"{key} must be a number, got {value!r}")
    if not math.isfinite(value):
        raise ConfigError(f"{key} must be a finite number, got {value}")
    if minimum is not None and value < minimum:
        raise ConfigError(f"{key} must be >= {minimum:g}, got {value:g}")
    if above is not None and not value > above:
        raise ConfigError(f"{key} must be > {above:g}, got {value:g}")


def at_least(
    obj: object,
    prefix: str,
    minimum: int,
    *names: str,
    error: type[ConfigError] = ConfigError,
) -> None:
    """Check that each integer field ``names`` of ``obj`` is ``>= minimum``.

    The type itself is :func:`check_fields`'s check; a non-integer is refused here too,
    so the rule holds whichever runs first.

    Args:
        obj: A dataclass instance.
        prefix: How its keys are named in messages, e.g. ``"collector."``.
        minimum: The smallest value allowed.
        *names: The fields to check.
        error: The error to raise (a layout's sizes raise :class:`LayoutError`).

    Raises:
        ConfigError: A field is not an integer or is below ``minimum`` (the message
            names ``prefix + name``).
    """
    for name in names:
        value = getattr(obj, name)
        if not _is_int(value):
            raise error(f"{prefix}{name} must be an integer, got {value!r}")
        if value < minimum:
            raise error(f"{prefix}{name} must be >= {minimum}, got {value}")


def _is_int(value: object) -> bool:
    return isinstance(value, (int, np.integer)) and not isinstance(value, (bool, np.bool_))


def _check_union(key: str, value: object, args: tuple[Any, ...]) -> None:
    if value is None and type(None) in args:
        return
    options = [a for a in args if a is not type(None)]
    first: ConfigError | None = None
    for option in options:
        try:
            check_value(key, value, option)
            return
        except ConfigError as exc:
            first = first or exc
    if value is None:
        raise ConfigError(f"{key} must be set, got null")
    assert first is not None  # a union has at least one non-None member
    raise first


def _check_items(key: str, value: object, args: tuple[Any, ...]) -> None:
    if isinstance(value, np.ndarray):
        value = value.tolist()
    if not isinstance(value, (list, tuple)):
        raise ConfigError(f"{key} must be a list, got {value!r}")
    item = args[0] if args and (len(args) == 1 or args[-1] is Ellipsis) else Any
    for i, v in enumerate(value):
        check_value(f"{key}[{i}]", v, item)


@cache
def _hints(cls: type) -> dict[str, Any]:
    # Annotations are strings (``from __future__ import annotations``); resolve them once
    # per class. A name that cannot be resolved is not checked rather than an error.
    try:
        return typing.get_type_hints(cls)
    except (NameError, TypeError):
        return {}
