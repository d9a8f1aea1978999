"""The fleet's guide paths between timesteps: the Python side of traffic-flow guidance.

The compiled kernels (:mod:`~rtaw_marl.sim.mapf._guidance`) plan, walk and compact the
paths; :class:`GuidePaths` owns their arrays (every path in one buffer, the edge flows,
the A* scratch) and calls them once per timestep for the whole fleet: advance every
robot along its path, plan a new path where one is needed (a new goal, a robot pushed
off its path), and, with ``replans``, re-plan that many more on the current flows, the
longest unchanged first.
"""

from __future__ import annotations

import numpy as np

from rtaw_marl.sim.mapf._guidance import (
    guide_advance,
    guide_compact,
    guide_drop,
    guide_plan,
    guide_ties,
)

__all__ = ["GuidePaths"]


class GuidePaths:
    """Every robot's guide path and the flows they make.

    Args:
        nbr: ``int32 [C, 4]`` the compact graph's neighbours.
        robots: ``M``.
        weight: Cost of one other guide path using an edge the other way.
        replans: Paths re-planned per timestep besides the needed ones.
    """

    def __init__(self, nbr: np.ndarray, robots: int, weight: float, replans: int) -> None:
        self.nbr, self.weight, self.replans = nbr, float(weight), int(replans)
        c, m = len(nbr), robots
        self._capacity = 8 * c + 64 * m
        self.buf = np.empty(self._capacity, dtype=np.int64)
        self.start = np.full(m, -1, dtype=np.int64)
        self.length = np.zeros(m, dtype=np.int64)
        self.at = np.zeros(m, dtype=np.int64)
        self.flow = np.zeros((c, 4), dtype=np.int32)
        self.need = np.zeros(m, dtype=bool)
        self.planned_at = np.zeros(m, dtype=np.int64)
        self._cost, self._parent = np.zeros(c), np.zeros(c, dtype=np.int64)
        self._stamp = np.full(c, -1, dtype=np.int64)
        self._heap_key, self._heap_node = np.empty(4 * c), np.empty(4 * c, dtype=np.int64)
        self._cursor = 0
        self._epoch = 0
        #: Guide paths planned in the episode.
        self.planned = 0

    def ties(self, pos: np.ndarray, tie: np.ndarray) -> None:
        """Mark each robot's next guide cell (and staying) in PIBT's ``tie [M, 5]``."""
        guide_ties(pos, self.buf, self.start, self.length, self.at, self.nbr, tie)

    def update(
        self, pos: np.ndarray, goal: np.ndarray, goal_field: np.ndarray, fields: np.ndarray,
        t: int,
    ) -> None:  # fmt: skip
        """After timestep ``t``'s moves: advance every robot along its path; plan the
        needed paths and ``replans`` more (``fields`` are the goals' BFS fields, the A*
        heuristic)."""
        guide_advance(
            pos, goal, self.buf, self.start, self.length, self.at, self.flow, self.nbr,
            self.need,
        )  # fmt: skip
        robots = np.flatnonzero(self.need).astype(np.int64)
        self.planned_at[robots] = t
        if self.replans:
            kept = np.flatnonzero((self.start >= 0) & ~self.need)
            old = kept[np.argsort(self.planned_at[kept], kind="stable")[: self.replans]]
            guide_drop(old, self.buf, self.start, self.length, self.at, self.flow, self.nbr)
            self.planned_at[old] = t
            robots = np.concatenate([robots, old])
        done = 0
        while done < len(robots):
            self._cursor, planned = guide_plan(
                robots[done:], pos, goal, goal_field, fields, self.nbr, self.flow,
                self.weight, self.buf, self._cursor, self.start, self.length, self.at,
                self._cost, self._parent, self._stamp, self._epoch + done, self._heap_key,
                self._heap_node,
            )  # fmt: skip
            done += planned
            if done < len(robots):
                self._compact()
        self._epoch += len(robots)
        self.planned += len(robots)

    def _compact(self) -> None:
        """Keep only the cells still to walk, in a buffer sized by them (twice, and room
        for a path of every cell): it does not grow with the episode."""
        live = int((self.length - self.at)[self.start >= 0].sum())
        out = np.empty(max(self._capacity, 2 * live + 2 * len(self.nbr)), np.int64)
        self._cursor = guide_compact(self.buf, self.start, self.length, self.at, out)
        self.buf = out
