"""The own executor as LoRR's planner (:class:`FleetPlanner`), driven by a stand-in for
LoRR's simulator that applies its action model: forward into the faced cell, quarter
turns, waits; a timestep with a vertex or swap conflict is refused (everyone waits), as
LoRR does. The real start kit runs it in ``test_lorr_kit.py``."""

from __future__ import annotations

import numpy as np
import pytest

from rtaw_marl.integrations.lorr.planner import FleetPlanner
from rtaw_marl.sim.layout import Layout
from rtaw_marl.sim.lorr import read_problem

pytestmark = pytest.mark.integration

#: Cell offsets (dx, dy) of LoRR's orientations: east, south, west, north.
_AHEAD = np.array([[1, 0], [0, 1], [-1, 0], [0, -1]])


def _apply(
    layout: Layout, loc: np.ndarray, heading: np.ndarray, actions: np.ndarray
) -> tuple[np.ndarray, np.ndarray, bool]:
    """LoRR's move of the fleet; returns the new cells and headings and whether valid."""
    w = layout.width
    x, y = loc % w, loc // w
    fw = actions == 0
    nx, ny = x + fw * _AHEAD[heading, 0], y + fw * _AHEAD[heading, 1]
    inside = (nx >= 0) & (nx < w) & (ny >= 0) & (ny < layout.height)
    if not inside.all() or layout.obstacles[ny, nx].any():
        return loc, heading, False
    new = ny * w + nx
    turn = np.where(actions == 1, 1, np.where(actions == 2, 3, 0))
    swaps = {(a, b) for a, b in zip(loc.tolist(), new.tolist(), strict=True) if a != b}
    valid = len(set(new.tolist())) == len(new) and not any((b, a) in swaps for a, b in swaps)
    if not valid:
        return loc, heading, False
    return new, (heading + turn) % 4, True


def test_planner_drives_lorrs_action_model_without_conflicts() -> None:
    problem = read_problem("builtin:random_32_32_20_100.json")
    layout = problem.layout()
    rng = np.random.default_rng(0)
    free = np.flatnonzero(~layout.obstacles.ravel())
    loc = rng.choice(free, size=100, replace=False)
    heading = np.zeros(100, dtype=np.int64)
    goals = rng.choice(free, size=100)
    planner = FleetPlanner(layout, 100, patience=8, guidance=1.0, guide_replans=0, seed=0)
    reached = 0
    for _ in range(200):
        actions = planner.plan(loc, heading, goals)
        assert set(np.unique(actions).tolist()) <= {0, 1, 2, 3}
        loc, heading, valid = _apply(layout, loc, heading, actions)
        assert valid
        at = loc == goals
        reached += int(at.sum())
        goals = np.where(at, rng.choice(free, size=100), goals)
    assert planner.mismatches == 0  # LoRR's cells and headings are the ones it predicted
    assert reached >= 300  # 473 with this seed: a floor any working planner clears
    assert planner.counts()["turn_actions"] > 0


def test_planner_replans_robots_it_did_not_predict() -> None:
    """A robot LoRR moved elsewhere (here: every action refused once) is planned from
    where LoRR says it is."""
    layout = read_problem("builtin:random_32_32_20_100.json").layout()
    free = np.flatnonzero(~layout.obstacles.ravel())
    loc, heading = free[:10].copy(), np.zeros(10, dtype=np.int64)
    planner = FleetPlanner(layout, 10, patience=8, guidance=0.0, guide_replans=0, seed=1)
    goals = free[-10:]
    actions = planner.plan(loc, heading, goals)
    assert (actions != 3).any()
    planner.plan(loc, heading, goals)  # LoRR refused the timestep: nobody moved
    assert planner.mismatches > 0
