"""Trained RTAW networks as greedy policies on the bare simulator, loaded from checkpoints."""

from __future__ import annotations

from pathlib import Path

import torch

from rtaw_marl.envs.features import sim_observation
from rtaw_marl.models.checkpoint import Actor, load_checkpoint, load_networks
from rtaw_marl.sim.core import WarehouseSim

__all__ = ["SimNetworkPolicy", "load_policy"]


def load_policy(path: str | Path, name: str | None = None) -> SimNetworkPolicy:
    """A greedy policy from a checkpoint; it runs on any ``M``, ``N``, layout or navigator.

    Args:
        path: The checkpoint file.
        name: Label in result tables; ``rtaw:<path>`` by default.

    Raises:
        ConfigError: The checkpoint is missing, unreadable, unsafe, for another feature
            layout, or its weights do not fit its model.
    """
    actor, _ = load_networks(load_checkpoint(path), path)
    return SimNetworkPolicy(actor, name=name or f"rtaw:{path}")


class SimNetworkPolicy:
    """Greedy (argmax) RTAW decisions on a bare simulator, for evaluation.

    Args:
        net: A trained policy network.
        name: Label used in result tables.
    """

    def __init__(self, net: Actor, name: str = "rtaw") -> None:
        self.net = net.eval()
        self.name = name

    def reset(self, seed: int | None = None) -> None:
        """Nothing to seed: greedy decisions are deterministic."""

    @torch.no_grad()
    def act_sim(self, sim: WarehouseSim) -> int:
        """The slot with the largest logit among the non-empty ones."""
        obs = sim_observation(sim, self.net.in_keys)
        logits = self.net(*(torch.from_numpy(obs[key]) for key in self.net.in_keys))
        mask = torch.from_numpy(obs["action_mask"])
        return int(torch.where(mask, logits, -torch.inf).argmax())
