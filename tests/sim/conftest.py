"""Shared fixtures of the simulator tests: the data-map folder and the paper's PoC setup."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest

from rtaw_marl.sim.config import SimConfig
from rtaw_marl.sim.core import WarehouseSim
from rtaw_marl.sim.distances import EuclideanDistance
from rtaw_marl.sim.layout import open_grid
from rtaw_marl.sim.tasks import POC_TASKS, FixedTasks

#: Real warehouse maps kept next to the repository (the large ones are not copied into it;
#: rtaw_marl/maps/ ships a few small ones, tests/sim/test_builtin_maps.py).
MAPS_DIR = Path(__file__).resolve().parents[2].parent / "shared" / "maps"


@pytest.fixture
def maps_dir() -> Path:
    """The shared data-map folder; skips the test when it is not present."""
    if not (MAPS_DIR / "README.md").is_file():
        pytest.skip(f"shared data maps not found at {MAPS_DIR}")
    return MAPS_DIR


@pytest.fixture
def poc_sim() -> Callable[..., WarehouseSim]:
    """Factory of the paper's proof-of-concept simulator (10x10 open grid, direct, 2 robots).

    Keyword arguments override :class:`SimConfig` fields.
    """

    def make(**overrides: object) -> WarehouseSim:
        values: dict[str, object] = {
            "num_robots": 2,
            "num_tasks": 5,
            "queue_len": 2,
            "noise_mean": 0.0,
            "noise_var": 0.0,
            "robot_starts": ((2, 2), (6, 2)),
            "robot_free_times": (0.0, 2.0),
        }
        values.update(overrides)
        layout = open_grid(10, 10)
        config = SimConfig(**values)  # type: ignore[arg-type]
        return WarehouseSim(config, layout, EuclideanDistance(layout), FixedTasks(POC_TASKS))

    return make
