"""Leftovers of a killed atomic write: its temporary files, found and removed.

:func:`~rtaw_marl.utils.atomic.atomic_write` writes ``.<name>.XXXXXXXX.tmp`` beside its
target and renames it over the target at the end. A process killed in between (``kill
-9``, a machine that lost power) leaves that temporary file, as large as the output,
and nothing else ever removes it. A writer that holds its output's claim
(:func:`~rtaw_marl.utils.runs.claim_file`) knows no other live process writes that name,
so every such file beside it is a leftover and can go.
"""

from __future__ import annotations

import re
from pathlib import Path

from rtaw_marl.utils.atomic import temp_name

__all__ = ["remove_stale_temps", "stale_temps"]

# mkstemp's random characters (tempfile._RandomNameSequence): lower-case letters,
# digits and "_".
_RANDOM = "[a-z0-9_]"


def _pattern(name: str) -> re.Pattern[str]:
    """The names :func:`~rtaw_marl.utils.atomic.temp_name` describes for ``name``."""
    # temp_name gives ".<name>.XXXXXXXX.tmp": its X count is the random part's length,
    # kept in one place (atomic.py) rather than copied here.
    count = temp_name(name).count("X") - name.count("X")
    return re.compile(rf"\.{re.escape(name)}\.{_RANDOM}{{{count}}}\.tmp")


def stale_temps(path: str | Path) -> list[Path]:
    """The temporary files of an atomic write of ``path`` present beside it, by name.

    Only names of exactly the shape ``.<name>.XXXXXXXX.tmp`` for ``path``'s own name
    count: another output's leftovers and other hidden files are not touched.
    """
    path = Path(path)
    pattern = _pattern(path.name)
    try:
        names = [entry.name for entry in path.parent.iterdir()]
    except OSError:  # no folder yet: nothing left over
        return []
    return sorted(
        path.parent / n for n in names if pattern.fullmatch(n) and (path.parent / n).is_file()
    )


def remove_stale_temps(path: str | Path) -> list[Path]:
    """Remove what a killed earlier atomic write of ``path`` left beside it.

    Call it only while holding ``path``'s claim (:func:`~rtaw_marl.utils.runs.claim_file`):
    the claim is what guarantees that no live process is writing one of these files.

    Returns:
        The files removed (the caller may say so).
    """
    removed = []
    for leftover in stale_temps(path):
        leftover.unlink(missing_ok=True)
        removed.append(leftover)
    return removed
