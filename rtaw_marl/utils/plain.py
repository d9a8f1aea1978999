"""Typed configs as plain values, for results files and checkpoints."""

from __future__ import annotations

import dataclasses
from typing import Any

__all__ = ["as_plain"]


def as_plain(obj: Any) -> Any:
    """Dataclasses as dicts, tuples as lists, recursively; other values unchanged."""
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        return {f.name: as_plain(getattr(obj, f.name)) for f in dataclasses.fields(obj)}
    if isinstance(obj, dict):
        return {k: as_plain(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [as_plain(v) for v in obj]
    return obj
