"""Config keys that were renamed: the one-line error for an old key typed on a command
line, and stored configs and commands read under today's names.

The simulator's config group was called ``env`` before it was ``sim``: ``env`` also
names the PettingZoo / Gymnasium environment (``warehouse_v1.env(...)``). Everything
written before the rename says ``env``: the shipped checkpoints' ``config`` and
``command``, older runs, ``results.json`` files (``config.env``), their
``.hydra/overrides.yaml`` (``env.num_robots=...``) and episode journals. Their readers
pass them through :func:`upgrade_config` and :func:`upgrade_command`; a person typing
``env.num_robots=50`` gets one line naming ``sim.num_robots`` (:func:`renamed_key`).

Each function takes the table of renamed sections: :data:`RENAMED` (every command with
the simulator's keys) by default; ``rtaw-train`` adds its own
(:data:`rtaw_marl.training.config.RENAMED`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

__all__ = ["RENAMED", "renamed_key", "upgrade_command", "upgrade_config"]

#: Sections renamed since, in every command with the simulator's keys: old name ->
#: (new name, what the new one is), the second for the one-line error of an old key.
RENAMED: Mapping[str, tuple[str, str]] = {
    "env": ("sim", "the simulator's keys; env names the PettingZoo env"),
}


def renamed_key(key: str, renamed: Mapping[str, tuple[str, str]] = RENAMED) -> str | None:
    """The one-line error for a renamed key (``env.num_robots``: ``env.num_robots is now
    sim.num_robots (the simulator's keys; env names the PettingZoo env)``); ``None`` for
    any other key. A bare section (``env=default``, the group's option) is renamed too."""
    head, dot, rest = key.partition(".")
    if head not in renamed:
        return None
    new, what = renamed[head]
    return f"{key} is now {new}{dot}{rest} ({what})"


def upgrade_config(
    config: Mapping[str, Any], renamed: Mapping[str, tuple[str, str]] = RENAMED
) -> dict[str, Any]:
    """A stored config under today's names: an old ``env`` section is ``sim``, in the
    same place (a checkpoint's ``config``, a results file's, a journal's setting). A
    config already under today's names comes back as it was (a copy); one holding both
    spellings keeps today's."""
    out: dict[str, Any] = {}
    for key, value in config.items():
        new = renamed[key][0] if key in renamed else None
        if new is None:
            out[key] = value
        elif new not in config:
            out[new] = value
    return out


def upgrade_command(
    command: Sequence[str], renamed: Mapping[str, tuple[str, str]] = RENAMED
) -> list[str]:
    """A recorded command or overrides list spelled with today's keys:
    ``env.num_robots=100`` is ``sim.num_robots=100`` (``+`` and ``~`` kept), ``env=default``
    is ``sim=default``; anything else is kept as it was."""
    out = []
    for arg in command:
        key, sep, value = arg.partition("=")
        head, dot, rest = key.partition(".")
        bare = head.lstrip("+~")
        group, at, package = bare.partition("@")
        if (sep or head.startswith("~")) and group in renamed:
            prefix = head[: len(head) - len(bare)]
            arg = f"{prefix}{renamed[group][0]}{at}{package}{dot}{rest}{sep}{value}"
        out.append(arg)
    return out
