"""Shared helpers of the MAPF kernel tests."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rtaw_marl.sim.mapf._pibt import bfs_compact, compact_graph


@dataclass
class RandomFleet:
    """Robots on a random share of a random 7x9 grid's free cells, with random goals
    (80% of robots have one), in the arrays the PIBT kernels take."""

    rng: np.random.Generator
    cells: np.ndarray
    nbr: np.ndarray
    pos: np.ndarray
    fields: np.ndarray
    goal_field: np.ndarray
    occ_now: np.ndarray
    occ_next: np.ndarray
    nxt: np.ndarray

    @property
    def m(self) -> int:
        return len(self.pos)


def random_fleet(seed: int, fill: float) -> RandomFleet | None:
    """A :class:`RandomFleet` filling ``fill`` of the cells; ``None`` for a grid with fewer
    than two free cells."""
    rng = np.random.default_rng(seed)
    obstacles = rng.random((7, 9)) < 0.2
    _, cells, nbr = compact_graph(obstacles)
    if len(cells) < 2:
        return None
    m = max(1, int(fill * len(cells)))
    pos = rng.choice(len(cells), m, replace=False).astype(np.int64)
    goals = rng.choice(len(cells), m).astype(np.int64)
    fields = np.empty((m, len(cells)), dtype=np.int32)
    for r in range(m):
        bfs_compact(nbr, int(goals[r]), fields[r])
    occ_now = np.full(len(cells), -1, dtype=np.int64)
    occ_now[pos] = np.arange(m)
    goal_field = np.where(rng.random(m) < 0.8, np.arange(m), -1).astype(np.int64)
    return RandomFleet(
        rng, cells, nbr, pos, fields, goal_field, occ_now,
        np.full(len(cells), -1, dtype=np.int64), np.empty(m, dtype=np.int64),
    )  # fmt: skip
