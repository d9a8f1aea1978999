"""TorchRL wrappers of the RTAW network, and a policy that drives the bare simulator."""

from __future__ import annotations

import numpy as np
import torch
from tensordict.nn import TensorDictModule
from torchrl.modules import MaskedCategorical, ProbabilisticActor, ValueOperator

from rtaw_marl.models.rtaw import RTAWActor, RTAWCritic
from rtaw_marl.sim.core import WarehouseSim
from rtaw_marl.sim.features import OBSERVATION_KEYS, robot_features, task_features

__all__ = ["OBSERVATION_KEYS", "SimNetworkPolicy", "make_actor", "make_critic"]


def make_actor(net: RTAWActor, keys: tuple = OBSERVATION_KEYS) -> ProbabilisticActor:
    """A stochastic actor: logits -> ``MaskedCategorical`` over the queue slots.

    Args:
        net: The policy network.
        keys: The observation keys in the order ``(robots, tasks, agent, action_mask)``;
            nested keys are allowed (the PettingZoo interop route uses them).

    Returns:
        A module writing ``"logits"``, ``"action"`` and ``"action_log_prob"``.
    """
    # Outputs go next to the action mask: ("agents", ...) on the interop route.
    prefix = keys[3][:-1] if isinstance(keys[3], tuple) else ()
    logits_key = (*prefix, "logits") if prefix else "logits"
    action_key = (*prefix, "action") if prefix else "action"
    module = TensorDictModule(net, in_keys=list(keys), out_keys=[logits_key])
    return ProbabilisticActor(
        module,
        in_keys={"logits": logits_key, "mask": keys[3]},
        out_keys=[action_key],
        distribution_class=MaskedCategorical,
        return_log_prob=True,
        log_prob_key=(*prefix, "action_log_prob") if prefix else "action_log_prob",
    )


def make_critic(net: RTAWCritic, keys: tuple = OBSERVATION_KEYS) -> ValueOperator:
    """A value module writing ``"state_value"`` (next to the observation keys)."""
    # Outputs go next to the action mask: ("agents", ...) on the interop route.
    prefix = keys[3][:-1] if isinstance(keys[3], tuple) else ()
    out = (*prefix, "state_value") if prefix else "state_value"
    return ValueOperator(net, in_keys=list(keys), out_keys=[out])


class SimNetworkPolicy:
    """Greedy (argmax) RTAW decisions on a bare simulator, for evaluation.

    Args:
        net: A trained policy network.
        name: Label used in result tables.
    """

    def __init__(self, net: RTAWActor, name: str = "rtaw") -> None:
        self.net = net.eval()
        self.name = name

    def reset(self, seed: int | None = None) -> None:
        """Nothing to seed: greedy decisions are deterministic."""

    @torch.no_grad()
    def act_sim(self, sim: WarehouseSim) -> int:
        """The slot with the largest logit among the non-empty ones."""
        scale = sim.layout.scale
        robots = robot_features(sim.robot_xy, sim.robot_free_at, sim.time, scale)
        tasks = task_features(
            sim.queue_rows, sim.queue_length, sim.robot_distances(), sim.queue_mask, scale
        )
        mask = torch.from_numpy(sim.queue_mask.copy())
        logits = self.net(
            torch.from_numpy(robots),
            torch.from_numpy(tasks),
            torch.from_numpy(np.ascontiguousarray(robots[sim.robot])),
            mask,
        )
        return int(torch.where(mask, logits, -torch.inf).argmax())
