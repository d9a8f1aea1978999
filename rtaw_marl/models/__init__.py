"""The RTAW network and its TorchRL actor/critic wrappers."""

from __future__ import annotations

from rtaw_marl.models.actor_critic import make_actor, make_critic
from rtaw_marl.models.rtaw import RTAWActor, RTAWCritic, RTAWEncoder

__all__ = [
    "RTAWActor",
    "RTAWCritic",
    "RTAWEncoder",
    "make_actor",
    "make_critic",
]
