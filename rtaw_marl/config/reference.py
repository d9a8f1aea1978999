"""The key reference of ``docs/configuration.md``, generated from the schemas.

Each schema documents its keys in its docstring's ``Attributes:`` section; this module
turns every registered option into a table (key, default, meaning), and refuses a key
that is not documented, so the reference can never fall behind the code.
"""

from __future__ import annotations

import dataclasses
import inspect
import re

from rtaw_marl.config.store import APPS, GROUPS

__all__ = ["key_reference", "undocumented_keys"]

_ATTR = re.compile(r"^(\w+):\s*(.*)$")


def attribute_docs(schema: type) -> dict[str, str]:
    """``Attributes:`` entries of ``schema`` and its bases, as one line each."""
    docs: dict[str, str] = {}
    for cls in reversed(schema.__mro__):
        text = inspect.getdoc(cls) if cls.__doc__ else None
        if not text or "Attributes:" not in text:
            continue
        key = None
        for line in text.split("Attributes:", 1)[1].splitlines()[1:]:
            if line and not line.startswith(" "):
                break  # the next section
            match = (
                _ATTR.match(line.strip())
                if line.startswith("    ") and not line.startswith("        ")
                else None
            )
            if match:
                key = match.group(1)
                docs[key] = match.group(2)
            elif key and line.strip():
                docs[key] += " " + line.strip()
    return docs


def undocumented_keys() -> list[str]:
    """``group/option: key`` for every schema key without an ``Attributes:`` entry."""
    missing = []
    for label, schema in _schemas():
        docs = attribute_docs(schema)
        missing += [f"{label}: {f.name}" for f in dataclasses.fields(schema) if f.name not in docs]
    return missing


def key_reference() -> str:
    """Markdown tables of every key of every option and app."""
    parts = []
    for label, schema in _schemas():
        docs = attribute_docs(schema)
        rows = [
            f"| `{f.name}` | {_default(f)} | {docs.get(f.name, '')} |"
            for f in dataclasses.fields(schema)
            if f.name != "name"
        ]
        if not rows:
            rows = ["| (none) | | |"]
        source = f"`{schema.__module__}.{schema.__qualname__}`"
        parts.append(f"### {label}\n\n{source}\n\n| key | default | meaning |\n|---|---|---|")
        parts.append("\n".join(rows) + "\n")
    return "\n".join(parts)


def _schemas() -> list[tuple[str, type]]:
    out: list[tuple[str, type]] = []
    for app, schema in APPS.items():
        out.append((f"{app} (top level)", schema))
        out += _sections(app, schema)
    for group, options in GROUPS.items():
        for name, schema in options.items():
            out.append((f"{group}={name}", schema))
            out += _sections(group, schema, sep=".")  # collector.ray.*
    return out


def _sections(prefix: str, schema: type, sep: str = ": ") -> list[tuple[str, type]]:
    """Nested dataclass fields (``collector``, ``eval``, ``baselines``) as their own tables."""
    grouped = {cls for options in GROUPS.values() for cls in options.values()}
    out = []
    for f in dataclasses.fields(schema):
        if f.default_factory is not dataclasses.MISSING:
            value = f.default_factory()
            if dataclasses.is_dataclass(value) and type(value) not in grouped:
                out.append((f"{prefix}{sep}{f.name}.*", type(value)))
    return out


def _default(f: dataclasses.Field) -> str:
    if f.default is not dataclasses.MISSING:
        value = f.default
    elif f.default_factory is not dataclasses.MISSING:
        value = f.default_factory()
    else:
        return "required" if f.type not in ("Any",) else "(config group)"
    if dataclasses.is_dataclass(value):
        return "(section below)"
    text = "null" if value is None else str(value).lower() if isinstance(value, bool) else value
    return f"`{text}`"
