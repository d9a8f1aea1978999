"""Each decision of a policy, related to what MPDM and ``lookahead`` would choose there.

:func:`play` runs a policy's own greedy episodes; at every decision a :class:`Probe`
asks MPDM (nearest task) and ``lookahead`` what they would choose in the same state
(they only read the simulator) and classifies the policy's choice as a
:class:`Decision`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from rtaw_marl.decision.features import RELATION_FEATURES, sim_relations
from rtaw_marl.evaluation.evaluate import SimPolicy
from rtaw_marl.policies import make_baseline
from rtaw_marl.policies.lookahead import lookahead_costs
from rtaw_marl.sim.core import WarehouseSim

__all__ = ["Decision", "Probe", "end_distances", "lookahead_set", "play", "ties"]

#: The reference rule, asked at every decision and played for reference.
LOOKAHEAD = "lookahead"
#: Relative tolerance of a tie, as the rules use it (``baselines._TIE_RTOL``).
TIE_RTOL = 1e-6
#: A rival "arrives first" when its arrival minus ``k`` is below this (units of ``L``).
RIVAL_EPS = 1e-6
RIVAL_1 = RELATION_FEATURES.index("rival_1")
CHAIN = RELATION_FEATURES.index("chain")


@dataclass(frozen=True)
class Decision:
    """How one choice relates to MPDM's and lookahead's in the same state.

    Attributes:
        nearest: The chosen task is a nearest one (MPDM's choice, up to ties).
        lookahead: The chosen task is one of lookahead's choices.
        lookahead_nearest: Lookahead would pick a nearest task.
        extra: ``k_chosen - k_nearest`` in cells (0 when ``nearest``).
        contested: Every nearest task has a rival arriving before the acting robot.
        chosen_free: No rival arrives at the chosen task before the acting robot.
        shorter_chain: The chosen task's chain is shorter than every nearest task's.
    """

    nearest: bool
    lookahead: bool
    lookahead_nearest: bool
    extra: float
    contested: bool
    chosen_free: bool
    shorter_chain: bool


class Probe:
    """MPDM and lookahead asked about the current state; their own tie-breaking
    generators are separate from any policy driving the simulator.

    Args:
        sim: The simulator the rules are bound to (its distance model, scale and noise).
    """

    def __init__(self, sim: WarehouseSim) -> None:
        self.mpdm = make_baseline("mpdm", env=sim)
        self.lookahead = make_baseline(LOOKAHEAD, env=sim)
        self.horizon: int = self.lookahead.horizon

    def reset(self, seed: int) -> None:
        """Reset both rules' tie-breaking for an episode of ``seed``."""
        self.mpdm.reset(seed)
        self.lookahead.reset(seed)

    def classify(self, sim: WarehouseSim, slot: int) -> Decision:
        """Relate ``slot``, about to be given to the selected robot, to the rules' choices.

        Raises:
            RuntimeError: A rule's own choice lies outside the tie set computed here.
        """
        mask = sim.queue_mask
        k = sim.robot_distances()
        nearest = ties(k, mask)
        ahead = lookahead_set(sim, self.horizon)
        for rule, allowed in ((self.mpdm, nearest), (self.lookahead, ahead)):
            if not allowed[rule.act_sim(sim)]:  # act_sim only reads the simulator
                raise RuntimeError(f"{rule.name} chose outside its tie set at t={sim.time}")
        relations, _ = sim_relations(sim)
        first = mask & (relations[:, RIVAL_1] < -RIVAL_EPS)
        chain = relations[:, CHAIN]
        return Decision(
            nearest=bool(nearest[slot]),
            lookahead=bool(ahead[slot]),
            lookahead_nearest=bool((ahead & nearest).any()),
            extra=float(k[slot] - k[mask].min()),
            contested=bool(first[nearest].all()),
            chosen_free=not bool(first[slot]),
            shorter_chain=bool(chain[slot] < chain[nearest].min()),
        )


def ties(values: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """``bool [N]``: the masked slots whose value is the smallest, within :data:`TIE_RTOL`."""
    best = float(values[mask].min())
    return mask & (values <= best + TIE_RTOL * max(1.0, best))


def end_distances(sim: WarehouseSim) -> np.ndarray:
    """``float64 [M + N, N]``: distances from each robot's cell (rows ``0..M-1``), then
    from each queued destination, to each queued origin; ``inf`` in empty slots' columns
    (rows of empty slots hold meaningless values that the rollout never reads)."""
    ends = np.vstack([sim.distance_matrix(), sim.chain_distances()])
    ends[:, ~sim.queue_mask] = np.inf
    return ends


def lookahead_set(sim: WarehouseSim, horizon: int) -> np.ndarray:
    """``bool [N]``: the slots of least lookahead cost (``Lookahead.act_sim`` picks one)."""
    mask = sim.queue_mask
    costs = lookahead_costs(
        sim.robot_distances(), end_distances(sim), sim.robot, sim.robot_free_at, sim.time,
        sim.queue_length, mask, horizon, sim.config.noise_mean,
    )  # fmt: skip
    return ties(costs, mask)


def play(
    sim: WarehouseSim, policy: SimPolicy, seeds: Sequence[int]
) -> tuple[list[Decision], list[float]]:
    """Run ``policy``'s own episodes and classify each of its decisions.

    Returns:
        Every decision over all seeds, and the TTD of each episode.
    """
    probe = Probe(sim)
    decisions, ttds = [], []
    for seed in seeds:
        sim.reset(seed)
        policy.reset(seed)
        probe.reset(seed)
        while not sim.done:
            slot = policy.act_sim(sim)
            decisions.append(probe.classify(sim, slot))
            sim.step(slot)
        ttds.append(sim.metrics().ttd)
    return decisions, ttds
