"""A small, valid LoRR output file to break one field at a time (the reader's tests and
the command's), on the map of ``tests.cli.test_eval_cli._tiny_lorr_problem``."""

from __future__ import annotations

import copy
import json
from pathlib import Path
from typing import Any

import numpy as np

from rtaw_marl.sim.layout import Layout

#: The 6 x 3 map of the tiny LoRR problem: obstacles at (row 1, column 1) and (1, 4).
TINY_MAP = ("......", ".@..@.", "......")

#: Two robots, three timesteps (``rtaw-render``'s ``MAPF`` model). Robot 0 goes right
#: along row 0 to its task 0's first errand (0, 2) at t = 2 and stays there; robot 1
#: goes left along row 2 and does task 1: errand (2, 4) at t = 2, (2, 3) at t = 3.
VALID: dict[str, Any] = {
    "actionModel": "MAPF",
    "teamSize": 2,
    "numTaskFinished": 1,
    "start": [[0, 0, "N/A"], [2, 5, "N/A"]],
    "actualPaths": ["R,R,W", "W,L,L"],
    "tasks": [[0, 0, [0, 2, 0, 3]], [1, 0, [2, 4, 2, 3]], [2, 1, [0, 5, 2, 0]]],
    "events": [[2, 0, 0, 1], [2, 1, 1, 1], [3, 1, 1, 2]],
    "actualSchedule": ["0:0", "1:1"],
}

#: The same episode in LoRR's turning model: robot 0 faces east and moves forward;
#: robot 1 faces south, turns clockwise once (west), then moves forward twice.
VALID_TURNING: dict[str, Any] = {
    **VALID,
    "actionModel": "MAPF_T",
    "start": [[0, 0, "E"], [2, 5, "S", "W"]],  # how lifelong v2.1.2 writes "S"
    "actualPaths": ["F,F,W", "R,F,F"],
}


def tiny_layout() -> Layout:
    """The map as a :class:`Layout`."""
    return Layout(np.array([[c == "@" for c in row] for row in TINY_MAP]), name="tiny")


def valid(model: str = "MAPF") -> dict[str, Any]:
    """A fresh copy of :data:`VALID` (``"MAPF_T"``: :data:`VALID_TURNING`)."""
    return copy.deepcopy(VALID if model == "MAPF" else VALID_TURNING)


def write(path: Path, data: Any) -> Path:
    """``data`` as JSON at ``path`` (``NaN`` allowed, as Python's json writes it)."""
    path.write_text(json.dumps(data), encoding="utf-8")
    return path
