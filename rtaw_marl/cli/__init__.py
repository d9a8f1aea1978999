"""Command-line entry points (thin Hydra mains)."""

from __future__ import annotations

from pathlib import Path

#: The Hydra config folder (``conf/`` at the repository root).
CONF_DIR = Path(__file__).resolve().parents[2] / "conf"
