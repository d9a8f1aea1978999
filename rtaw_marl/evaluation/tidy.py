"""The per-episode table: one row per (policy, seed), every metric a column.

``results.json`` keeps each policy's metrics as lists over the seeds; this is the same
data as a tidy table that ``pandas.read_csv`` loads as is (no melting):

    policy,seed,ttd,makespan,...,wall_time_s
    mpdm,0,1234.5,...
"""

from __future__ import annotations

import csv
import io
from collections.abc import Mapping, Sequence
from pathlib import Path

from rtaw_marl.utils.atomic import atomic_write

__all__ = ["csv_text", "episode_rows", "write_episodes_csv"]


def episode_rows(
    results: Mapping[str, Mapping[str, Sequence[float]]], seeds: Sequence[int]
) -> list[dict[str, str | int | float]]:
    """``[{"policy", "seed", metric: value, ...}]`` in policy then seed order.

    Args:
        results: ``{policy: {metric: [one value per seed]}}`` (what
            :func:`~rtaw_marl.evaluation.evaluate` returns).
        seeds: The seeds, in the order of the value lists.

    Raises:
        ValueError: A metric's list does not have one value per seed.
    """
    rows: list[dict[str, str | int | float]] = []
    for policy, metrics in results.items():
        for name, values in metrics.items():
            if len(values) != len(seeds):
                raise ValueError(f"{policy}.{name} has {len(values)} values for {len(seeds)} seeds")
        for i, seed in enumerate(seeds):
            rows.append({"policy": policy, "seed": seed, **{k: v[i] for k, v in metrics.items()}})
    return rows


def write_episodes_csv(
    path: str | Path,
    results: Mapping[str, Mapping[str, Sequence[float]]],
    seeds: Sequence[int],
) -> Path:
    """Write :func:`episode_rows` as CSV, atomically. Columns: ``policy``, ``seed``, then
    every metric any policy has, in first-seen order (a metric a policy lacks is empty).
    """
    data = csv_text(episode_rows(results, seeds), ["policy", "seed"]).encode()
    atomic_write(Path(path), lambda fh: fh.write(data))
    return Path(path)


def csv_text(rows: Sequence[Mapping[str, object]], first: Sequence[str] = ()) -> str:
    """``rows`` as CSV text: the columns ``first``, then every other key of any row in
    first-seen order; a key a row lacks, or a ``None`` value, is an empty cell."""
    columns: dict[str, None] = dict.fromkeys(first)
    for row in rows:
        columns.update(dict.fromkeys(row))
    text = io.StringIO()
    writer = csv.DictWriter(text, fieldnames=list(columns), lineterminator="\n")
    writer.writeheader()
    writer.writerows(rows)
    return text.getvalue()
