"""TorchRL environments (the batched native env)."""

from __future__ import annotations

from rtaw_marl.envs.batched import OBSERVATION_KEYS, BatchedWarehouseEnv

__all__ = ["OBSERVATION_KEYS", "BatchedWarehouseEnv"]
