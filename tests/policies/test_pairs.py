"""The winner's greedy pair matching (``rtaw_marl.policies.pairs``) and ``pair_greedy``
in the own simulator."""

from __future__ import annotations

import numpy as np
import pytest

from rtaw_marl.policies import make_baseline
from rtaw_marl.policies.pairs import PairGreedy, greedy_pairs, pair_costs
from rtaw_marl.sim.core import WarehouseSim

pytestmark = pytest.mark.unit


def _reference(cost: np.ndarray) -> np.ndarray:
    """Greedy matching by the definition: all pairs sorted by (cost, row, column)."""
    rows, cols = cost.shape
    out = np.full(rows, -1)
    used_r: set[int] = set()
    used_c: set[int] = set()
    keys = np.lexsort(
        (np.tile(np.arange(cols), rows), np.repeat(np.arange(rows), cols), cost.ravel())
    )
    for idx in keys.tolist():
        r, c = divmod(idx, cols)
        if r not in used_r and c not in used_c:
            out[r] = c
            used_r.add(r)
            used_c.add(c)
    return out


@pytest.mark.parametrize("k", [1, 3, 100])
@pytest.mark.parametrize("ties", [True, False])
def test_greedy_pairs_is_the_greedy_matching(k: int, ties: bool) -> None:
    """Equal to the definition on random matrices, many ties (integer costs) or none,
    for lists shorter than a row (the scan takes over) and longer."""
    rng = np.random.default_rng(7)
    for _ in range(150):
        rows, cols = rng.integers(1, 30, size=2)
        cost = rng.integers(0, 12, (rows, cols)).astype(float) if ties else rng.random((rows, cols))
        got = greedy_pairs(cost, k=k)
        np.testing.assert_array_equal(got, _reference(cost))
        assert (got >= 0).sum() == min(rows, cols)
        assert len(set(got[got >= 0].tolist())) == (got >= 0).sum()


def test_greedy_pairs_empty_and_costs() -> None:
    assert greedy_pairs(np.zeros((0, 3))).shape == (0,)
    np.testing.assert_array_equal(greedy_pairs(np.zeros((2, 0))), [-1, -1])
    cost = pair_costs(np.array([[1.0, 2.0]]), np.array([10.0, 3.0]))
    np.testing.assert_array_equal(cost, [[15.0, 13.0]])


def _lorr_sim(reassign: bool = True, horizon: int = 150) -> WarehouseSim:
    from rtaw_marl.scenarios.lorr import lorr_scenario
    from rtaw_marl.sim.builder import build_sim

    scenario = lorr_scenario("builtin:random_32_32_20_100.json", horizon=horizon, reassign=reassign)
    return build_sim(scenario.spec())


def test_pair_greedy_reassigns_in_the_own_simulator() -> None:
    """On LoRR's random map it takes held tasks (the executor counts the robots
    released), its episodes repeat for a seed, and its schedule passes the checker."""
    from rtaw_marl.sim.mapf.conflicts import check_schedule

    policy = make_baseline("pair_greedy")
    assert isinstance(policy, PairGreedy)
    finished = []
    for _ in range(2):
        sim = _lorr_sim()
        sim.reset(3)
        policy.reset(3)
        while not sim.done:
            sim.step(policy.act_sim(sim))
        finished.append(sim.metrics().tasks_finished)
        assert sim.executor.stats()["reassigned"] > 0
    assert finished[0] == finished[1] > 0
    check_schedule(sim.layout, sim.schedule())


def test_pair_greedy_re_pairs_holders_each_timestep() -> None:
    """Holders matched to another task give theirs back (``sim.release``) and take their
    match in the same timestep, as LoRR's re-pairing of every robot without a started
    task; every planned task is then legal for its robot."""
    sim = _lorr_sim(horizon=120)
    policy = PairGreedy()
    released: list[int] = []
    release = sim.release

    def spy(robots: np.ndarray) -> None:
        released.extend(np.asarray(robots).tolist())
        release(robots)

    sim.release = spy  # type: ignore[method-assign]
    sim.reset(4)
    policy.reset(4)
    while not sim.done:
        before = len(released)
        slot = policy.act_sim(sim)
        assert sim.legal_actions()[slot]
        if len(released) > before:
            now = sim.time
            freed = set(sim.free_robots().tolist())
            assert set(released[before:]) <= freed
            assert all(t == now for t in sim.robot_free_at[released[before:]])
        sim.step(slot)
    assert released
    assert sim.metrics().tasks_finished > 0


def test_pair_greedy_without_reassignment_takes_queued_tasks() -> None:
    sim = _lorr_sim(reassign=False, horizon=60)
    policy = PairGreedy()
    sim.reset(0)
    while not sim.done:
        slot = policy.act_sim(sim)
        assert sim.queue_mask[slot]
        sim.step(slot)
    assert "reassigned" not in sim.executor.stats()


def test_pair_greedy_acts_on_the_simulator_only() -> None:
    with pytest.raises(NotImplementedError, match="act_sim"):
        PairGreedy().act({})
