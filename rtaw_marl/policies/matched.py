"""A learned policy's decisions in batches: every free robot of a timestep at once.

A :class:`~rtaw_marl.policies.network.NetworkPolicy` decides one robot after another,
each decision a network call; at thousands of robots a timestep frees dozens, and inside
LoRR's clock the robots not served in time wait (``deferred``). :class:`MatchedPolicy`
decides them together, at the first decision of each timestep:

1. each free robot's ``K`` candidate tasks: the queued origins nearest it, exactly the
   slots its own decision would score (``candidates=K``);
2. one network call scores every robot's candidates, each robot seeing the decision as
   it would if it were acting now (:func:`~rtaw_marl.decision.features.decision_features`
   with ``viewers``; the acting robot's row is its own decision's, up to which of the
   rivals arriving at exactly the same time are kept);
3. a greedy matching on the log-probabilities (the most confident pair first, each robot
   and task at most once: :func:`~rtaw_marl.policies.pairs.greedy_pairs`) turns the
   scores into tasks, so two robots never both want the nearest task of both.

A caller out of time (LoRR's clock) sends the matches not yet taken as they are
(:meth:`MatchedPolicy.pending`): a batch's robots are then all served, though the
simulator selects robots by id and a batch is chosen by place.

The robots then take their matches as the simulator selects them. A timestep that frees
more than :data:`BATCH` robots (every robot at t = 0) is matched a batch at a time, each
call bounded so LoRR's clock can stop between them: the selected robot with the free
robots nearest it (grid distance; they compete for the same tasks, and their candidates
overlap, so a batch's distance fields are few), the tasks promised to robots of earlier
batches left out. A robot whose candidates all went to others decides alone, as the
wrapped policy does. Decisions are deterministic.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from rtaw_marl.errors import ConfigError, missing_extra

# Without the training extra: one error that names it, as the network policies'.
try:
    import torch
except ModuleNotFoundError as exc:
    raise missing_extra(exc, __name__, "train") from None

from rtaw_marl.decision.features import decision_features
from rtaw_marl.decision.schema import Decision
from rtaw_marl.policies.network import NetworkPolicy
from rtaw_marl.policies.pairs import greedy_pairs
from rtaw_marl.sim.core import WarehouseSim

__all__ = ["BATCH", "MatchedPolicy", "nearest_slots"]

#: Robots matched by one network call: a timestep that frees more (every robot at
#: t = 0) is matched a batch at a time, so one call stays within a fraction of LoRR's
#: clock and the robots left over can wait.
BATCH = 32

#: Cost of a pair outside a robot's candidates: above any ``-log p`` a float32 softmax
#: gives (``-log`` of the smallest positive float32 is about 104), so never preferred.
_OUTSIDE = 1.0e6


class MatchedPolicy:
    """A learned policy deciding a timestep's free robots together (module docstring).

    Args:
        policy: The network policy; its ``candidates=K`` bounds each robot's tasks.
        name: Label in result tables (default: the policy's with ``+matched``).

    Raises:
        ConfigError: The policy has no ``candidates`` (every queued task for every free
            robot would not fit a timestep at LoRR's sizes).
    """

    def __init__(self, policy: NetworkPolicy, name: str | None = None) -> None:
        if policy.candidates is None:
            raise ConfigError("policy=matched needs candidates=K (for example candidates=32)")
        self.policy = policy
        self.name = name or f"{policy.name}+matched"
        self.reset()

    @property
    def candidates(self) -> int:
        """``K``: the tasks scored per robot."""
        return int(self.policy.candidates)  # type: ignore[arg-type]

    def reset(self, seed: int | None = None) -> None:
        """Forget the timestep's matching (greedy decisions: the seed is unused)."""
        del seed
        self._plan: tuple[tuple[int, float], dict[int, tuple[int, int]]] | None = None
        self._asked = np.zeros(0, dtype=bool)  # robots matched this timestep
        #: Decisions served by a match, and decided alone (no match, or it was taken).
        self.served = self.alone = 0

    def act_sim(self, sim: WarehouseSim) -> int:
        """The selected robot's match, or its own decision when it has none.

        The first robot of a timestep without a match so far is matched with the
        :data:`BATCH` ``- 1`` free robots nearest it not yet matched (itself first)."""
        key = (id(sim), sim.time)
        if self._plan is None or self._plan[0] != key:
            self._plan, self._asked = (key, {}), np.zeros(sim.num_robots, dtype=bool)
        plan = self._plan[1]
        if not self._asked[sim.robot]:
            robots = self._batch(sim)
            self._asked[robots] = True
            # The slots promised to robots of earlier batches, not yet served.
            promised = np.zeros(sim.queue_len, dtype=bool)
            promised[_pairs(plan)[1]] = True
            plan.update(self.match(sim, robots, exclude=promised))
        planned = plan.pop(sim.robot, None)
        if planned is not None:
            slot, task = planned
            if sim.queue_ids[slot] == task and sim.queue_mask[slot]:
                self.served += 1
                return slot
        self.alone += 1
        return self.policy.act_sim(sim)

    def pending(self, sim: WarehouseSim) -> tuple[np.ndarray, np.ndarray]:
        """The robots matched this timestep and not yet served, and their slots
        (``int64 [P]`` each, by robot), the matched tasks still queued: decisions made,
        which a caller out of time (LoRR's clock) may send as they are."""
        current = self._plan is not None and self._plan[0] == (id(sim), sim.time)
        robots, slots, tasks = _pairs(self._plan[1] if current else {})  # type: ignore[index]
        live = sim.queue_mask[slots] & (sim.queue_ids[slots] == tasks)
        order = np.argsort(robots[live], kind="stable")
        return robots[live][order], slots[live][order]

    def _batch(self, sim: WarehouseSim) -> np.ndarray:
        """``int64 [<= BATCH]``: the selected robot, then the free robots not yet matched
        nearest it on the grid (ties to the lower id), in id order."""
        free = sim.free_robots()
        free = free[~self._asked[free] & (free != sim.robot)]
        if len(free) > BATCH - 1:
            gap = np.abs(sim.robot_xy[free] - sim.robot_xy[sim.robot]).sum(axis=1)
            free = free[np.sort(np.argsort(gap, kind="stable")[: BATCH - 1])]
        return np.concatenate([[sim.robot], free]).astype(np.int64)

    def match(
        self,
        sim: WarehouseSim,
        robots: np.ndarray | None = None,
        exclude: np.ndarray | None = None,
    ) -> dict[int, tuple[int, int]]:
        """Robot -> ``(slot, task)`` for ``robots int [R]`` (default: every robot free
        now), from one network call; ``exclude bool [N]`` marks slots no robot may take
        (promised to another)."""
        robots = sim.free_robots() if robots is None else np.asarray(robots, dtype=np.int64)
        if not sim.queue_mask.any():
            return {}
        slots, logp = self.scores(sim, robots, exclude)
        columns, pos = np.unique(slots[slots >= 0], return_inverse=True)
        cost = np.full((len(robots), len(columns)), _OUTSIDE)
        rows = np.broadcast_to(np.arange(len(robots))[:, None], slots.shape)[slots >= 0]
        cost[rows, pos] = -logp[slots >= 0]
        got = greedy_pairs(cost)
        plan = {}
        for robot, row, col in zip(robots.tolist(), range(len(robots)), got.tolist(), strict=True):
            if col >= 0 and cost[row, col] < _OUTSIDE:
                slot = int(columns[col])
                plan[robot] = (slot, int(sim.queue_ids[slot]))
        return plan

    @torch.no_grad()
    def scores(
        self, sim: WarehouseSim, robots: np.ndarray, exclude: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """Each robot's candidates and the network's log-probabilities of them.

        Args:
            sim: The simulator at a decision.
            robots: ``int [R]`` robots, each seen as if it were acting now.
            exclude: ``bool [N]`` slots left out of the candidates (promised to robots
                of an earlier batch); the decision still shows them queued.

        Returns:
            ``slots int64 [R, K]`` (ascending per row; ``-1`` pads rows with fewer than
            ``K`` queued tasks) and ``logp float32 [R, K]`` (``-inf`` on pads).
        """
        robots = np.asarray(robots, dtype=np.int64)
        mask = sim.queue_mask if exclude is None else sim.queue_mask & ~exclude
        # The key of NetworkPolicy.act_sim (distance / L in float32): the same K slots.
        near = sim.robot_distances_many(robots, np.arange(sim.queue_len))
        key = np.where(mask, (near / sim.layout.scale).astype(np.float32), np.inf)
        slots = nearest_slots(key, min(self.candidates, sim.queue_len))
        union, index = np.unique(slots, return_inverse=True)
        index = index.reshape(slots.shape)  # [R, K] columns of the union
        keys = frozenset(self.policy.feature_keys)
        decision = Decision.of_sim(sim, keys, union)
        features = decision_features(decision, keys, robots, index)
        valid = features["action_mask"] & mask[slots]
        inputs = [
            torch.from_numpy(np.require(features[name], np.float32, "CW"))
            for name in self.policy.feature_keys
        ]
        m = torch.from_numpy(np.require(valid, bool, "CW"))
        logits = self.policy.net(*inputs, m)
        logp = torch.log_softmax(torch.where(m, logits, -torch.inf), dim=-1).numpy()
        return np.where(valid, slots, -1), np.where(valid, logp, -np.inf).astype(np.float32)

    def act(self, observation: Mapping[str, Any]) -> int:
        """Not available: use :meth:`act_sim` (the matching needs every free robot).

        Raises:
            NotImplementedError: Always.
        """
        raise NotImplementedError(
            f"{self.name} acts on the simulator only (it matches every free robot at "
            "once); evaluate it with rtaw-eval or act_sim"
        )


def _pairs(plan: Mapping[int, tuple[int, int]]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A plan as arrays: its robots, their slots and tasks (``int64 [P]`` each)."""
    robots = np.fromiter(plan.keys(), dtype=np.int64, count=len(plan))
    pairs = np.array(list(plan.values()), dtype=np.int64).reshape(-1, 2)
    return robots, pairs[:, 0], pairs[:, 1]


def nearest_slots(key: np.ndarray, k: int) -> np.ndarray:
    """Each row's ``k`` smallest entries of ``key float [R, N]``, ties to the lower
    column, in column order: ``int64 [R, k]``, per row what
    :func:`~rtaw_marl.decision.features.candidate_slots` picks, in ``O(R N)`` (no sort)."""
    if k >= key.shape[1]:
        return np.broadcast_to(np.arange(key.shape[1]), key.shape).copy()
    part = np.argpartition(key, k - 1, axis=1)[:, :k]
    cut = np.take_along_axis(key, part, axis=1).max(axis=1, keepdims=True)
    below = key < cut
    tied = key == cut
    # The first (k - below) tied columns of each row complete it.
    need = k - below.sum(axis=1, keepdims=True)
    keep = below | (tied & (np.cumsum(tied, axis=1) <= need))
    return np.nonzero(keep)[1].reshape(len(key), k).astype(np.int64)
