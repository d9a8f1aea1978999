"""Trained RTAW policies loaded from checkpoints, for evaluation."""

from __future__ import annotations

from pathlib import Path

from rtaw_marl.models.policy import SimNetworkPolicy
from rtaw_marl.training.checkpoint import build_networks, load_checkpoint

__all__ = ["load_policy"]


def load_policy(path: str | Path, name: str | None = None) -> SimNetworkPolicy:
    """A greedy policy from a checkpoint; it runs on any ``M``, ``N``, layout or navigator.

    Args:
        path: The checkpoint file.
        name: Label in result tables; ``rtaw:<path>`` by default.

    Raises:
        ConfigError: The checkpoint is missing, unreadable or for another feature layout.
    """
    ckpt = load_checkpoint(path)
    actor, _ = build_networks(ckpt["model_config"])
    actor.load_state_dict(ckpt["model"]["actor"])
    return SimNetworkPolicy(actor, name=name or f"rtaw:{path}")
