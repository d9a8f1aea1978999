"""``pair_greedy`` in LoRR's simulator: the 2024 winner's scheduler, with reassignment.

Every timestep (as ``Straple/OMAPFS``'s ``GreedyScheduler``): the robots without a
started task (free, or on their way to a first errand) and the tasks not started (not
assigned, or assigned and the first errand not reached) are matched greedily on
:func:`~rtaw_marl.policies.pairs.pair_costs` (5 x travel to the first errand + the task's
length), cheapest pair first (:func:`~rtaw_marl.policies.pairs.greedy_pairs`). A robot
may so lose a task it had not started, or get another one: LoRR's ``TaskManager``
allows both until the robot reaches the first errand. Robots with a started task keep it.

Differences from the winner's code, all in what it adds for its own planner: it hands
every robot left without a task some task (its planner needs a goal for each; the kit's
planner does not), and it refreshes each robot's sorted list only as its time allows
(here every list is computed every timestep; ``max_call_s`` says what that costs).
"""

from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np

from rtaw_marl.integrations.lorr.scheduler import SchedulerStats, Timestep
from rtaw_marl.policies.pairs import PAIR_WEIGHT, greedy_pairs, pair_costs
from rtaw_marl.sim.distances import GridDistance
from rtaw_marl.sim.layout import Layout

__all__ = ["PairScheduler"]


class PairScheduler:
    """LoRR's ``plan`` for the pair-greedy rule (the module docstring).

    Args:
        layout: The problem's map.
        distance_model: Distances on it (shortest paths).
        weight: Cost of a cell of travel to the first errand against one of the task's
            length.
        clock: Seconds (``time.perf_counter``).
        first_pickups: ``int [K, 2]`` pickup cells ``(x, y)`` of the problem's first
            tasks, whose distance fields :meth:`preload` computes.
    """

    def __init__(
        self,
        layout: Layout,
        distance_model: GridDistance,
        weight: float = PAIR_WEIGHT,
        clock: Callable[[], float] = time.perf_counter,
        first_pickups: np.ndarray | None = None,
    ) -> None:
        self.layout, self.distance_model = layout, distance_model
        self._first_pickups = np.zeros((0, 2), np.int64) if first_pickups is None else first_pickups
        self.weight, self.clock = float(weight), clock
        self.width = layout.width
        # The open tasks, in arrays: id, first errand (linearized cell), length (travel
        # through all errands), and whether its robot has reached the first errand.
        self._ids = np.zeros(0, dtype=np.int64)
        self._first = np.zeros(0, dtype=np.int64)
        self._length = np.zeros(0)
        self._started = np.zeros(0, dtype=bool)
        self.stats = SchedulerStats()

    def preload(self, budget_s: float) -> int:
        """Compute the distance fields of the first tasks' pickups in LoRR's preprocessing
        time (the first timestep pairs every robot with a whole window of tasks).

        Returns:
            The cells whose fields were computed within ``budget_s`` seconds.
        """
        cells = np.unique(np.asarray(self._first_pickups, dtype=np.int64), axis=0)
        deadline = self.clock() + budget_s
        done = 0
        while done < len(cells) and self.clock() < deadline:
            self.distance_model.fields(cells[done : done + 32])
            done = min(done + 32, len(cells))
        return done

    def plan(self, step: Timestep, budget_s: float) -> list[int]:
        """The schedule for this timestep: each robot's task id or ``-1``.

        Args:
            step: LoRR's state.
            budget_s: Seconds for scheduling (not enforced: one matching per timestep;
                the time taken is counted in ``stats``).
        """
        del budget_s
        start = self.clock()
        schedule = np.asarray(step.schedule, dtype=np.int64)
        self._sync(step)
        # LoRR is asked about a robot's task until it is known to be started (one call
        # into the kit per robot on its way to a first errand).
        at = np.searchsorted(self._ids, schedule)
        known = (schedule >= 0) & (at < len(self._ids))
        known[known] = self._ids[at[known]] == schedule[known]
        asked = np.zeros(len(schedule), dtype=bool)
        asked[known] = ~self._started[at[known]]
        for i in np.flatnonzero(asked).tolist():
            self._started[at[i]] = step.progress(int(schedule[i])) > 0
        started = np.zeros(len(schedule), dtype=bool)
        started[known] = self._started[at[known]]
        robots = np.flatnonzero(~started)
        open_ = np.flatnonzero(~self._started)
        proposed = schedule.copy()
        if len(robots) and len(open_):
            at_cells = np.asarray(step.locations, dtype=np.int64)[robots]
            cost = pair_costs(
                self.distance_model.distance_matrix(
                    self._xy(at_cells), self._xy(self._first[open_])
                ),
                self._length[open_], self.weight,
            )  # fmt: skip
            cols = greedy_pairs(cost)
            proposed[robots] = np.where(cols >= 0, self._ids[open_][np.maximum(cols, 0)], -1)
        else:
            proposed[robots] = -1
        changed = proposed != schedule
        self.stats.decisions += int((changed & (proposed >= 0)).sum())
        self.stats.reassigned += int((changed & (schedule >= 0)).sum())
        spent = self.clock() - start
        self.stats.calls += 1
        self.stats.seconds += spent
        self.stats.max_call_s = max(self.stats.max_call_s, spent)
        return proposed.tolist()

    def _sync(self, step: Timestep) -> None:
        """Drop the finished tasks, add the newly revealed ones (ids kept sorted)."""
        pool = np.fromiter((int(t) for t in step.pool), dtype=np.int64)
        keep = np.isin(self._ids, pool)
        new = np.setdiff1d(pool, self._ids)
        ids, first = self._ids[keep], self._first[keep]
        length, started = self._length[keep], self._started[keep]
        if len(new):
            errands = [np.asarray(step.read_task(int(t))[0], dtype=np.int64) for t in new]
            legs = self.distance_model.distance(
                self._xy(np.concatenate([e[:-1] for e in errands])),
                self._xy(np.concatenate([e[1:] for e in errands])),
            )
            ends = np.cumsum([len(e) - 1 for e in errands])
            ids = np.concatenate([ids, new])
            first = np.concatenate([first, [e[0] for e in errands]])
            length = np.concatenate([length, _sums(legs, ends)])
            started = np.concatenate([started, np.zeros(len(new), dtype=bool)])
        order = np.argsort(ids, kind="stable")
        self._ids, self._first = ids[order], first[order].astype(np.int64)
        self._length, self._started = length[order], started[order]

    def _xy(self, locs: np.ndarray) -> np.ndarray:
        locs = np.asarray(locs, dtype=np.int64)
        return np.stack([locs % self.width, locs // self.width], axis=-1)


def _sums(legs: np.ndarray, ends: np.ndarray) -> np.ndarray:
    """Each task's travel through its errands: its legs ``legs[ends[i-1]:ends[i]]``
    summed (a task of one errand has none: length 0)."""
    bounds = np.concatenate([[0], ends])
    cum = np.concatenate([[0.0], np.cumsum(legs)])
    return cum[bounds[1:]] - cum[bounds[:-1]]
