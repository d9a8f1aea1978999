"""``from rtaw_marl import warehouse_v1``: the versioned env module (PettingZoo convention)."""

from __future__ import annotations

from rtaw_marl.envs.pettingzoo import env, raw_env

__all__ = ["env", "raw_env"]
