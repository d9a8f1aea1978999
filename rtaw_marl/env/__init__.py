"""PettingZoo environments (no torch imports here)."""

from __future__ import annotations

from rtaw_marl.env.warehouse import env, raw_env

__all__ = ["env", "raw_env"]
