"""What a command reports (its tables and notes), printed and kept for its run folder.

``rtaw-eval`` prints its tables with ``print``, which Hydra's job
log (``eval.log``) never sees; a :class:`Transcript` prints each block to stdout as it
comes and saves the same text beside the results file (``results.txt`` beside
``results.json``), atomically. Progress (bars, time estimates) goes to stderr and is
not part of it, so ``rtaw-eval ... > table.txt`` and the saved file hold the same
report.
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import TextIO

from rtaw_marl.utils.atomic import atomic_write

__all__ = ["Transcript", "progress_shown", "transcript_path"]


def transcript_path(results: str | Path) -> Path:
    """Where the report of the results file ``results`` is saved: ``<stem>.txt``
    beside it (``results.json`` -> ``results.txt``; ``out.txt`` -> ``out.txt.txt``,
    never the results file itself)."""
    path = Path(results)
    if path.suffix == ".txt":
        return path.with_name(f"{path.name}.txt")
    return path.with_name(f"{path.stem}.txt")


def progress_shown(requested: bool, stream: TextIO | None = None) -> bool:
    """Whether to draw a progress bar on ``stream`` (stderr): when requested and the
    stream is a terminal. Redirected to a file or a pipe, a bar would leave a line per
    refresh (carriage returns) in the log."""
    stream = sys.stderr if stream is None else stream
    isatty = getattr(stream, "isatty", None)
    return requested and callable(isatty) and bool(isatty())


class Transcript:
    """Blocks of report text: printed as they come, saved together at the end.

    Args:
        stream: Where blocks are printed; ``None``: ``sys.stdout`` at the time of
            printing (so a test's capture sees them).
    """

    def __init__(self, stream: TextIO | None = None) -> None:
        self.stream = stream
        self.blocks: list[str] = []

    def print(self, text: str = "") -> None:
        """Print ``text`` (one or more lines) and keep it."""
        print(text, file=self.stream or sys.stdout, flush=True)
        self.blocks.append(text)

    def text(self) -> str:
        """Everything printed so far, one newline after each block."""
        return "".join(f"{block}\n" for block in self.blocks)

    def save(self, path: str | Path) -> Path:
        """Write :meth:`text` to ``path`` atomically; returns the path."""
        data = self.text().encode()
        return atomic_write(path, lambda fh: fh.write(data))
