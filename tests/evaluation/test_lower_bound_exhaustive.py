"""The TTD lower bound against the true optimum, found by exhaustive search.

Tiny random ``drain`` instances (layouts up to 5x5, open or with a few obstacles, 1-3
robots, 2-5 tasks, queue 1-3) small enough to try every sequence of valid actions. The
bound must never exceed the best episode TTD of any action sequence, whatever the
navigator (``direct``, ``astar``, with or without completion noise; ``sipp``, ``cbs``
with robots waiting for each other), the task stream (random, or fixed lists with
repeated cells and zero-length tasks) or the robots' first free times. Instances are
drawn from fixed seeds, so the test is deterministic (about 10 s on 2 cores).
"""

from __future__ import annotations

import zlib
from typing import Any

import numpy as np
import pytest

from rtaw_marl.errors import PlanningError
from rtaw_marl.evaluation.lower_bound import ttd_lower_bound
from rtaw_marl.sim.builder import SimSpec, build_sim
from rtaw_marl.sim.core import WarehouseSim
from rtaw_marl.sim.layout import Layout
from rtaw_marl.sim.tasks import FixedTasks, TaskStream

pytestmark = pytest.mark.integration

#: Completion noise ``(mean, var)`` per setting: none; the default; wide (draws below
#: minus the travel time: tasks may finish at their decision time, so robots need not
#: act in id order; a negative mean is refused).
NOISE = {"none": (0.0, 0.0), "default": (0.25, 0.25), "wide": (0.0, 9.0)}


def optimum(sim: WarehouseSim, seed: int) -> tuple[float, int]:
    """The smallest episode TTD over every sequence of valid actions (depth-first search).

    Each branch replays its action prefix from ``sim.reset(seed)``: the simulator has no
    cheap copy, and at these sizes a replay costs a few steps. A sequence that ends in a
    :class:`PlanningError` (collision-aware robots deadlocked, say two robots that must
    swap ends of a corridor) is no episode any policy can finish and is left out.

    Returns:
        The optimum (``inf`` when no sequence finishes) and how many sequences finished.
    """
    best, finished = np.inf, 0

    def replay(prefix: list[int]) -> None:
        sim.reset(seed)
        for action in prefix:
            sim.step(action)

    def search(prefix: list[int]) -> None:
        nonlocal best, finished
        if sim.done:
            best, finished = min(best, sim.metrics().ttd), finished + 1
            return
        assert np.isfinite(sim.time)  # a deadlock raises PlanningError instead
        fresh = True  # the first child continues from the current state
        for slot in np.flatnonzero(sim.queue_mask).tolist():
            if not fresh:
                replay(prefix)
            try:
                sim.step(slot)
            except PlanningError:
                fresh = False
                continue
            search([*prefix, slot])
            fresh = False

    replay([])
    search([])
    return float(best), finished


def tiny_layout(rng: np.random.Generator, min_side: int) -> Layout:
    """An open grid (sides from ``min_side``), or a small grid with 1-3 obstacles whose
    free cells are connected."""
    if rng.random() < 0.5:
        w, h = int(rng.integers(2, 6)), int(rng.integers(min_side, 5))
        return Layout(np.zeros((h, w), dtype=bool), name="open")
    w, h = int(rng.integers(3, 6)), int(rng.integers(3, 6))
    while True:
        obstacles = np.zeros((h, w), dtype=bool)
        obstacles.flat[rng.choice(w * h, size=int(rng.integers(1, 4)), replace=False)] = True
        layout = Layout(obstacles, name="obstacles")
        if len(layout.main_cells) == int((~obstacles).sum()):
            return layout


def tiny_tasks(rng: np.random.Generator, layout: Layout, count: int) -> TaskStream | str:
    """Random tasks, or a fixed list drawn with replacement (shared and zero-length tasks)."""
    if rng.random() < 0.5:
        return "random"
    cells = layout.main_cells
    picks = rng.integers(len(cells), size=(count, 2))
    return FixedTasks(np.concatenate([cells[picks[:, 0]], cells[picks[:, 1]]], axis=1))


def instance(index: int, navigator: str, noise: str) -> tuple[WarehouseSim, int]:
    """Tiny drain instance number ``index`` of a setting, and its episode seed."""
    rng = np.random.default_rng([index, zlib.crc32(f"{navigator}/{noise}".encode())])
    # Robots that wait for each other cannot pass in a one-row corridor: most action
    # sequences deadlock there, and CBS takes seconds to prove each one.
    layout = tiny_layout(rng, 2 if navigator in ("sipp", "cbs") else 1)
    free = len(layout.main_cells)
    robots = int(rng.integers(1, min(3, free - 1) + 1))
    tasks = int(rng.integers(2, 6))
    mean, var = NOISE[noise]
    keys: dict[str, Any] = {
        "num_robots": robots,
        "num_tasks": tasks,
        "queue_len": int(rng.integers(1, 4)),
        "episode_mode": "drain",
        "noise_mean": mean,
        "noise_var": var,
    }
    if rng.random() < 0.25:
        # Robots first free at different (whole-second) times: no id order to rely on.
        keys["robot_free_times"] = rng.integers(0, 4, size=robots).astype(float).tolist()
    # CBS's default budget (200 high-level nodes a call) spends seconds proving tiny
    # deadlocks; past 20 the new robot plans alone around the others, still collision-free.
    nav = {"name": "cbs", "max_nodes": 20} if navigator == "cbs" else navigator
    spec = SimSpec.of(keys, layout, nav, tiny_tasks(rng, layout, tasks))
    return build_sim(spec), int(rng.integers(2**31))


@pytest.mark.parametrize(
    ("navigator", "noise", "count"),
    [
        ("direct", "none", 300),
        ("direct", "default", 200),
        ("astar", "none", 300),
        ("astar", "default", 200),
        ("astar", "wide", 200),
        ("sipp", "none", 200),
        ("cbs", "none", 150),
    ],
)
def test_bound_never_exceeds_the_exhaustive_optimum(navigator: str, noise: str, count: int) -> None:
    """At least 100 instances per setting (about 1,500 in all) finish some sequence;
    on each the bound is at most the best TTD of any finished sequence."""
    checked = 0
    for index in range(count):
        sim, seed = instance(index, navigator, noise)
        best, finished = optimum(sim, seed)
        if not finished:
            continue  # every sequence deadlocks (collision-aware robots on a crowded grid)
        bound = ttd_lower_bound(sim, seed)
        assert bound <= best + 1e-9, (index, seed, bound, best)
        checked += 1
    assert checked >= min(100, count)
