"""The output file of a command that draws an episode (``rtaw-view``, ``rtaw-render``):
never one of its inputs, held by one run at a time, free of a killed run's leftovers.

* :func:`refuse_inputs`: an output that is the same file as something the command reads
  (a ``schedule=`` file, a LoRR problem, a layout or checkpoint file), however it is
  named (a relative path, a symbolic or hard link), is refused before any work.
* :func:`claimed_output`: the output is claimed for the run
  (:func:`~rtaw_marl.utils.runs.claim_file`, a lock beside it that the kernel drops
  when the process dies), so a second run writing the same file fails at once instead
  of silently replacing the first one's file; then the temporary files a killed earlier
  write of that name left behind (:mod:`rtaw_marl.utils.stale`) are removed.
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from rtaw_marl.errors import ConfigError
from rtaw_marl.utils.runs import claim_file

__all__ = ["claimed_output", "config_inputs", "refuse_inputs", "same_file"]

#: Keys of a command's config that are not inputs (what it writes, a page title).
_NOT_INPUTS = frozenset({"output", "title"})
#: Config groups nest no deeper than this (``navigator.*``, ``baselines.*``).
_DEPTH = 4


def same_file(a: str | Path, b: str | Path) -> bool:
    """Whether ``a`` and ``b`` name one file: the same path once links and ``..`` are
    resolved, or the same inode (a hard link)."""
    try:
        if os.path.samefile(a, b):
            return True
    except OSError:  # one does not exist (yet): only its resolved path can match
        pass
    return os.path.realpath(a) == os.path.realpath(b)


def config_inputs(cfg: Any) -> list[tuple[str, Path]]:
    """``(key, file)`` for every value of a typed command config that names an existing
    file (a string, or a string in a list), ``output`` and ``title`` left out."""
    found: list[tuple[str, Path]] = []

    def walk(node: Any, prefix: str, depth: int) -> None:
        for f in dataclasses.fields(node):
            if not prefix and f.name in _NOT_INPUTS:
                continue
            value, key = getattr(node, f.name), f"{prefix}{f.name}"
            if dataclasses.is_dataclass(value) and depth < _DEPTH:
                walk(value, f"{key}.", depth + 1)
                continue
            for item in value if isinstance(value, (list, tuple)) else [value]:
                if isinstance(item, str) and item and os.path.isfile(item):
                    found.append((key, Path(item)))

    walk(cfg, "", 0)
    return found


def refuse_inputs(
    output: str | Path, inputs: Sequence[tuple[str, Path]], what: str = "output"
) -> None:
    """Refuse an ``output`` that is one of the command's ``inputs`` (``(key, file)``).

    Raises:
        ConfigError: ``output`` is the same file as an input, named by its key.
    """
    for key, path in inputs:
        if same_file(output, path):
            raise ConfigError(
                f"{what}={output} is the same file as {key}={path}, which this command "
                f"reads; writing it would destroy its own input: choose another {what}"
            )


@contextmanager
def claimed_output(
    output: str | Path,
    inputs: Sequence[tuple[str, Path]] = (),
    what: str = "output",
    progress: Callable[[str], None] | None = None,
) -> Iterator[Path]:
    """Hold ``output`` for this run (see the module docstring).

    Args:
        output: The file the run writes (atomically, at the end).
        inputs: ``(key, file)`` the run reads; ``output`` must be none of them.
        what: The config key that named ``output``, for messages.
        progress: Told which leftovers were removed, if any.

    Yields:
        ``output`` as a :class:`~pathlib.Path`, held until the body ends.

    Raises:
        ConfigError: ``output`` is an input, another running process holds it, or it
            cannot be written (:func:`~rtaw_marl.utils.runs.check_writable_file`).
    """
    refuse_inputs(output, inputs, what)
    # The claim also removes what a killed earlier write of this name left.
    with claim_file(output, what, note=progress or (lambda line: None)) as path:
        yield path
