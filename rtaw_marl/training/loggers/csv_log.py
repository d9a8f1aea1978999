"""``logger=csv`` (the default): every scalar of a run in one CSV file,
``<run>/logs/metrics.csv``, and :func:`read_metrics` to read it back."""

from __future__ import annotations

import csv
import io
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from rtaw_marl.training.loggers.base import Backend
from rtaw_marl.training.loggers.config import FRAMES, LoggerConfig
from rtaw_marl.utils.atomic import atomic_write

__all__ = ["METRICS_CSV", "CSVMetrics", "read_metrics"]

#: The CSV logger's file, relative to the run folder.
METRICS_CSV = Path("logs") / "metrics.csv"


class CSVMetrics(Backend):
    """Every scalar of a run in one CSV file: a header row, then one row per step.

    Columns: ``frames`` first, then each scalar in the order it was first logged. A
    scalar first seen later (the evaluation's, the imitation warm start's) becomes a new
    last column, and the file is rewritten atomically with the union of the columns
    (earlier rows get empty cells): columns never move or disappear, so a reader by
    name (:class:`csv.DictReader`, ``pandas.read_csv``) reads every row alike.

    Rows: scalars logged at the same step merge into one row until a name repeats, so
    an iteration's evaluation and update share a row. A row is on disk once it is logged
    (appended, or the file rewritten atomically when a row or the columns change); a
    kill can tear only the last line, which a resume drops
    (:func:`~rtaw_marl.training.checkpoints.trim_csv_logs`). An existing file (a resumed
    run's) is continued with its columns.

    Args:
        path: The CSV file.
    """

    name = "csv"

    def __init__(self, path: Path) -> None:
        self.path = Path(path)
        self.columns: list[str] = [FRAMES]
        self.rows: list[dict[str, str]] = []
        # What the last row may still take: (step, axis); None for rows read from disk.
        self._open: tuple[int, str | None] | None = None
        if self.path.is_file():
            self._read()

    @classmethod
    def start(cls, option: LoggerConfig, run_dir: Path, config: Mapping[str, Any]) -> CSVMetrics:
        """The run's file, ``run_dir/logs/metrics.csv`` (:data:`METRICS_CSV`)."""
        return cls(Path(run_dir) / METRICS_CSV)

    def _read(self) -> None:
        with self.path.open(newline="") as fh:
            reader = csv.DictReader(fh)
            if reader.fieldnames and reader.fieldnames[0] == FRAMES:
                self.columns = list(reader.fieldnames)
                self.rows = [{k: v or "" for k, v in row.items() if k} for row in reader]

    def log(self, scalars: Mapping[str, float], step: int, axis: str | None = None) -> None:
        """Add ``scalars`` at ``step`` to the last row or as a new one, then write."""
        cells = {name: repr(float(value)) for name, value in scalars.items()}
        new = [name for name in cells if name not in self.columns]
        self.columns += new
        last = self.rows[-1] if self.rows else {}
        merge = self._open == (step, axis) and not any(last.get(name) for name in cells)
        if merge:
            last.update(cells)
        else:
            self.rows.append({FRAMES: str(int(step)), **cells})
            self._open = (step, axis)
        if new or merge or not self.path.is_file():
            atomic_write(self.path, self._write_all)
        else:
            with self.path.open("a", newline="") as fh:
                self._writer(fh).writerow(self.rows[-1])

    def _write_all(self, fh: Any) -> None:
        text = io.StringIO(newline="")
        writer = self._writer(text)
        writer.writeheader()
        writer.writerows(self.rows)
        fh.write(text.getvalue().encode())

    def _writer(self, fh: Any) -> csv.DictWriter:
        # "\n", as the rest of the run folder's text files (csv's default is "\r\n").
        return csv.DictWriter(fh, self.columns, restval="", lineterminator="\n")

    def close(self) -> None:
        """Nothing is buffered: every row is written when logged."""


def read_metrics(path: str | Path, column: str | None = None) -> list[dict[str, float]]:
    """The rows of a ``logger=csv`` file as ``{name: value}`` without the empty cells;
    with ``column``, only the rows that hold it.

    Example: the greedy TTD after each evaluation,
    ``[(r["frames"], r["eval/ttd"]) for r in read_metrics(path, "eval/ttd")]``.
    """
    with Path(path).open(newline="") as fh:
        rows = [{k: float(v) for k, v in row.items() if k and v} for row in csv.DictReader(fh)]
    return [row for row in rows if column is None or column in row]
