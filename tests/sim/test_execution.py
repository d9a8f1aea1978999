"""Executors: WarehouseSim behaves exactly as before the executor split, for each of them.

The golden values were recorded with the simulator before travel was delegated to
executors (when ``sipp``/``cbs`` were navigators owning a fleet); they must never change.
"""

from __future__ import annotations

import hashlib

import numpy as np
import pytest

from rtaw_marl.errors import ConfigError
from rtaw_marl.policies import make_baseline
from rtaw_marl.sim.builder import SimSpec, build_sim
from rtaw_marl.sim.config import SimConfig
from rtaw_marl.sim.core import WarehouseSim
from rtaw_marl.sim.distances import GridDistance
from rtaw_marl.sim.execution import InstantTravel
from rtaw_marl.sim.options import ShelvesLayoutConfig
from rtaw_marl.sim.tasks import RandomTasks

pytestmark = pytest.mark.unit

NOISELESS = {"noise_mean": 0.0, "noise_var": 0.0}
C = {"name": "preset", "preset": "C"}


def digest(*arrays: np.ndarray) -> str:
    m = hashlib.sha256()
    for a in arrays:
        m.update(np.ascontiguousarray(a).tobytes())
    return m.hexdigest()[:16]


def play_mpdm(sim: WarehouseSim, seed: int) -> tuple[list[str], str]:
    """An MPDM episode: exact metrics and a digest of robots, rewards and finish times."""
    policy = make_baseline("mpdm")
    policy.reset(seed=seed)
    sim.reset(seed)
    robots, rewards = [], []
    while not sim.done:
        robots.append(sim.robot)
        rewards.append(sim.step(policy.act_sim(sim)))
    m = sim.metrics()
    trace = digest(
        np.asarray(robots, dtype=np.int64), np.asarray(rewards, dtype=np.float64), sim.task_finished
    )
    return [repr(m.ttd), repr(m.makespan), repr(m.idle_mean)], trace


@pytest.mark.parametrize(
    ("navigator", "keys", "layout", "seed", "metrics", "trace"),
    [
        ("direct", {"num_robots": 10, "num_tasks": 60}, "shelves", 0,
         ["723.2163151484366", "293.4707342591764", "35.843477805887105"], "337bd632e8092c32"),
        ("astar", {"num_robots": 10, "num_tasks": 60, "episode_mode": "paper"}, "shelves", 1,
         ["743.0", "294.2934371122776", "37.92109396569661"], "b763ae314d6c8d17"),
        ("sipp", {"num_robots": 10, "num_tasks": 40, **NOISELESS}, C, 3,
         ["641.0", "249.0", "49.1"], "60229a0ab6a4864f"),
        ("cbs", {"num_robots": 10, "num_tasks": 40, **NOISELESS}, C, 3,
         ["650.0", "249.0", "48.6"], "9f89d72bba7dbb53"),
    ],
)  # fmt: skip
def test_episodes_match_the_recorded_simulator(
    navigator: str, keys: dict, layout: object, seed: int, metrics: list[str], trace: str
) -> None:
    sim = build_sim(SimSpec.of(keys, layout, navigator, "designated"))
    assert play_mpdm(sim, seed) == (metrics, trace)


@pytest.mark.parametrize(
    ("navigator", "positions", "stats"),
    [
        ("sipp", "33138a971460ac42", (43.0, 0.0, 0.0)),
        ("cbs", "ab08a61ce2448142", (49.0, 0.0, 0.0)),
    ],
)
def test_collision_aware_schedules_match_the_recorded_fleets(
    navigator: str, positions: str, stats: tuple[float, ...]
) -> None:
    sim = build_sim(
        SimSpec.of({"num_robots": 10, "num_tasks": 40, **NOISELESS}, C, navigator, "designated")
    )
    play_mpdm(sim, 3)
    assert digest(sim.schedule().positions.astype(np.int64)) == positions
    counters = sim.executor.stats()
    assert (counters["planning_calls"], counters["evacuations"], counters["cbs_fallbacks"]) == stats
    assert (sim.executor.name, sim.executor.collision_aware) == (navigator, True)


def test_instant_travel_is_the_default() -> None:
    """executor=None and an explicit InstantTravel give the same episode; no schedule."""
    layout = ShelvesLayoutConfig(width=30, height=20).build()
    config = SimConfig(num_robots=5, num_tasks=30)
    runs = []
    for executor in (None, InstantTravel()):
        sim = WarehouseSim(config, layout, GridDistance(layout), RandomTasks(),
                           executor=executor)  # fmt: skip
        runs.append(play_mpdm(sim, 7))
        assert isinstance(sim.executor, InstantTravel)
        assert (sim.executor.name, sim.executor.collision_aware) == ("instant", False)
        assert sim.executor.stats() == {}
        with pytest.raises(ConfigError, match="'astar' moves robots independently"):
            sim.schedule()
    assert runs[0] == runs[1]


def test_instant_travel_noise_never_finishes_before_the_decision() -> None:
    """A noise draw below minus the travel time is clipped at the decision time (the mean
    must be >= 0, but single draws of a wide noise still fall that low)."""
    keys = {"num_robots": 3, "num_tasks": 20, "noise_mean": 0.0, "noise_var": 10_000.0}
    sim = build_sim(SimSpec.of(keys, {"name": "open", "width": 8, "height": 8}, "direct", "random"))
    sim.reset(0)
    while not sim.done:
        sim.step(int(np.flatnonzero(sim.queue_mask)[0]))
    assert (sim.task_finished >= sim.task_assigned).all()
    assert (sim.task_finished == sim.task_assigned).any()
