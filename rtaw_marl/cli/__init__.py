"""Command-line entry points (thin Hydra mains)."""

from __future__ import annotations

from pathlib import Path

#: The Hydra config folder (``rtaw_marl/conf/``, shipped in the package).
CONF_DIR = Path(__file__).resolve().parents[1] / "conf"
