"""Search with a learned policy at decision time: ``lookahead`` with the network inside.

For the free robot, the network's ``width`` best slots (by logit) are each given to it
and then rolled forward ``horizon`` decisions on the *current queue only* (no future
tasks, no refills; the completion noise replaced by its mean; the next decision going to
the robot freed first), with the **network** choosing for each robot that frees next, as
``lookahead`` does with MPDM. A candidate's cost is the total pickup distance (the TTD)
of its ``horizon + 1`` decisions, minus ``leaf`` times the critic's value of the state
the rollout ends in, in cells (``leaf=0``: no critic). The cheapest candidate wins; ties
go to the larger logit. All candidates are rolled out at once: a rollout step is one
batched feature computation and one network call over ``[width, ...]``.

The rollout reads only what a decision's observation holds (robot cells and free times,
the queue) and the distance model, as ``lookahead`` does: nothing of the future (the
task stream, the noise draws) is seen, so the search is an honest online policy.

``width=1`` or ``horizon=0`` (without ``leaf``) is the network alone. With a scorer
that prefers the nearest task (:func:`nearest_scores`), :func:`search_costs` is
``lookahead``'s rollout exactly (tested), which is how this module's rollouts are checked.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from rtaw_marl.decision.features import Decision, decision_features, nearest_other

__all__ = [
    "Rollout",
    "Scorer",
    "nearest_scores",
    "rollout_start",
    "rollout_take",
    "search_costs",
    "top_slots",
]

#: ``(features {key: [B, ...]}) -> float [B, N]`` scores of each queued slot per row
#: (the larger, the more preferred; empty slots are masked by the caller).
Scorer = Callable[[dict[str, np.ndarray]], np.ndarray]


@dataclass(frozen=True)
class Rollout:
    """The arrays of one decision that a search rolls forward (never written).

    Attributes:
        robot: The free robot.
        now: The decision time.
        robot_xy: ``int [M, 2]`` the cell where each robot will next be free.
        free_at: ``float64 [M]`` when each robot is free.
        rows: ``int [N, 4]`` task cells per slot.
        lengths: ``float64 [N]`` origin -> destination length per slot.
        mask: ``bool [N]`` which slots hold a task.
        waits: ``float64 [N]`` time each task has waited in the queue.
        ends: ``float64 [M + N, N]`` distances from every robot's cell (rows ``0..M-1``)
            and every queued destination (rows ``M..``) to each queued origin, ``inf``
            for empty slots (:func:`~rtaw_marl.policies.lookahead.rollout_distances`).
        noise_mean: The completion noise's mean, used in place of the noise.
        scale: ``L``.
    """

    robot: int
    now: float
    robot_xy: np.ndarray
    free_at: np.ndarray
    rows: np.ndarray
    lengths: np.ndarray
    mask: np.ndarray
    waits: np.ndarray
    ends: np.ndarray
    noise_mean: float
    scale: float

    @cached_property
    def cells(self) -> np.ndarray:
        """``int [M + N, 2]``: the cell of each row of :attr:`ends` (robots, then the
        queued destinations), computed once per decision."""
        return np.concatenate([self.robot_xy, self.rows[:, 2:]])

    @cached_property
    def finite_ends(self) -> np.ndarray:
        """:attr:`ends` with the empty slots' ``inf`` as 0 (the features mask them)."""
        return np.where(np.isfinite(self.ends), self.ends, 0.0)


def top_slots(scores: np.ndarray, mask: np.ndarray, width: int) -> np.ndarray:
    """``int64 [min(width, queued)]`` the queued slots of the ``width`` largest scores,
    best first (ties: the lowest slot)."""
    live = np.flatnonzero(mask)
    order = np.argsort(-scores[live], kind="stable")
    return live[order[:width]]


def search_costs(
    state: Rollout,
    candidates: np.ndarray,
    horizon: int,
    scorer: Scorer,
    keys: tuple[str, ...],
    leaf: Callable[[dict[str, np.ndarray]], np.ndarray] | None = None,
) -> np.ndarray:
    """Cost of giving each candidate slot to the free robot, rolled out ``horizon``
    decisions with ``scorer`` choosing (module docstring).

    Args:
        state: The decision.
        candidates: ``int [B]`` slots to try (each must hold a task).
        horizon: Decisions simulated after the candidate's own.
        scorer: Scores the queued slots of a batch of rollout decisions' features.
        keys: The feature keys ``scorer`` (and ``leaf``) read.
        leaf: ``features -> float [B]``: a value, in cells, subtracted from the cost of
            each rollout's final state (the critic, scaled); ``None``: none.

    Returns:
        ``float64 [B]`` cost per candidate: pickup distance over the rollout, less the
        leaf value.
    """
    m = len(state.free_at)
    k = np.arange(len(candidates))
    ends = state.ends
    cost = ends[state.robot, candidates].astype(np.float64)
    free, where, left = rollout_start(
        state.robot, state.now, state.free_at, state.mask, state.lengths, state.noise_mean,
        candidates, cost,
    )  # fmt: skip
    for _ in range(horizon):
        if not left.any():
            break
        nxt = free.argmin(axis=1)  # ties: the lowest robot id, as the simulator
        t = free[k, nxt]
        scores = scorer(_features(state, free, where, left, nxt, t, keys))
        j = np.where(left, scores, -np.inf).argmax(axis=1)
        live = left[k, j]  # rollouts that still had a task to take
        dj = np.where(live, ends[where[k, nxt], j], 0.0)
        cost += dj
        rollout_take(free, where, left, nxt, j, dj, live, state.lengths, state.noise_mean, m)
    if leaf is not None:
        nxt = free.argmin(axis=1)
        cost -= leaf(_features(state, free, where, left, nxt, free[k, nxt], keys))
    return cost


def rollout_start(
    robot: int,
    now: float,
    free_at: np.ndarray,
    mask: np.ndarray,
    lengths: np.ndarray,
    noise_mean: float,
    candidates: np.ndarray,
    first: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """One rollout per candidate slot, the free ``robot`` given it at ``now`` (``first
    float [B]``: its distance to each): ``free float64 [B, M]`` free times, ``where int
    [B, M]`` the row of ``ends`` each robot stands at (its cell, or ``M + slot`` of the
    task it delivers last), ``left bool [B, N]`` the tasks still queued."""
    m, b = len(free_at), len(candidates)
    k = np.arange(b)
    free = np.tile(free_at, (b, 1))
    where = np.tile(np.arange(m), (b, 1))
    left = np.tile(mask, (b, 1))
    free[k, robot] = np.maximum(now, now + first + lengths[candidates] + noise_mean)
    where[k, robot] = m + candidates
    left[k, candidates] = False
    return free, where, left


def rollout_take(
    free: np.ndarray,
    where: np.ndarray,
    left: np.ndarray,
    nxt: np.ndarray,
    j: np.ndarray,
    dj: np.ndarray,
    live: np.ndarray,
    lengths: np.ndarray,
    noise_mean: float,
    m: int,
) -> None:
    """In place: in each rollout ``b`` where ``live[b]``, robot ``nxt[b]`` takes slot
    ``j[b]`` at distance ``dj[b]`` (free again after it and the task's length, with the
    noise's mean); the other rollouts are left as they are."""
    k = np.arange(len(nxt))
    t = free[k, nxt]
    finish = np.maximum(t, t + dj + lengths[j] + noise_mean)
    free[k, nxt] = np.where(live, finish, t)
    where[k, nxt] = np.where(live, m + j, where[k, nxt])
    left[k[live], j[live]] = False


def _features(
    state: Rollout,
    free: np.ndarray,
    where: np.ndarray,
    left: np.ndarray,
    nxt: np.ndarray,
    t: np.ndarray,
    keys: tuple[str, ...],
) -> dict[str, np.ndarray]:
    """The observation entries ``keys`` of ``B`` rollout decisions: ``free float [B, M]``
    free times, ``where int [B, M]`` rows of ``ends`` the robots stand at, ``left bool
    [B, N]`` tasks still queued, ``nxt int [B]`` acting robots at times ``t float [B]``."""
    m, n = len(state.free_at), len(state.mask)
    dist = state.finite_ends[where]  # [B, M, N]
    b = len(nxt)
    decision = Decision(
        robot_xy=state.cells[where],
        free_at=free,
        time=t,
        robot=nxt,
        queue_rows=np.broadcast_to(state.rows, (b, n, 4)),
        queue_length=np.where(left, state.lengths, 0.0),
        queue_mask=left,
        scale=state.scale,
        own_distances=dist[np.arange(b), nxt],
        distances=dist,
        waits=np.where(left, state.waits + (t - state.now)[:, None], 0.0),
        nearest=nearest_other(np.broadcast_to(state.ends[m:], (b, n, n)), left),
    )
    return decision_features(decision, keys)


def nearest_scores(features: dict[str, np.ndarray]) -> np.ndarray:
    """MPDM as a scorer: minus the acting robot's distance to each origin (``tasks``
    column 4, or ``relations`` column 0), ties to the lowest slot as ``argmax`` breaks
    them. With it, :func:`search_costs` is ``lookahead``'s rollout."""
    if "relations" in features:
        return -features["relations"][..., 0].astype(np.float64)
    return -features["tasks"][..., 4].astype(np.float64)
