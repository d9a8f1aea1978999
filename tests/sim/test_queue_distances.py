"""The kept fleet-to-queue and chain distances equal fresh ones at every decision."""

from __future__ import annotations

import numpy as np
import pytest

import rtaw_marl.sim.distances as distances
from rtaw_marl.policies import MPDM
from rtaw_marl.sim.builder import SimSpec, build_sim
from rtaw_marl.sim.core import WarehouseSim
from rtaw_marl.sim.queue_distances import nearest_other_origin

pytestmark = pytest.mark.unit


def _sim(navigator: str, **overrides: object) -> WarehouseSim:
    values: dict[str, object] = {"num_robots": 7, "num_tasks": 60, "queue_len": 5}
    values.update(overrides)
    layout = {"name": "shelves", "width": 16, "height": 12} if navigator != "direct" else {
        "name": "open", "width": 14, "height": 14}  # fmt: skip
    return build_sim(SimSpec.of(values, layout, navigator, "random"))


def _fresh_nearest(sim: WarehouseSim, slots: np.ndarray) -> np.ndarray:
    """``chain_nearest(slots)`` computed from scratch: each destination's distances to
    every origin, the other queued slots' minimum."""
    chain = sim._slots.distances_from(sim.queue_rows[slots, 2:])
    other = np.broadcast_to(sim.queue_mask, chain.shape).copy()
    other[np.arange(len(slots)), slots] = False
    nearest = np.where(other, chain, np.inf).min(axis=-1, initial=np.inf)
    return np.where(sim.queue_mask[slots], nearest, np.inf)


def _check_along_episode(sim: WarehouseSim, seed: int, policy: object = None) -> int:
    """Play MPDM (or ``policy``); at every decision compare the kept matrices and the
    kept nearest origins of a few slots (all of them every fifth decision) with fresh
    ones."""
    every = np.arange(sim.queue_len)
    rng = np.random.default_rng(seed)
    sim.reset(seed)
    policy = policy or MPDM()
    policy.reset(seed)
    checked = 0
    while not sim.done:
        if sim.queue_len <= 64:
            np.testing.assert_array_equal(sim.distance_matrix(), sim.distance_matrix(every))
            np.testing.assert_array_equal(sim.chain_nearest(), _fresh_nearest(sim, every))
        some = every if checked % 5 == 0 else rng.choice(every, size=min(6, len(every)))
        np.testing.assert_array_equal(sim.chain_nearest(some), _fresh_nearest(sim, some))
        checked += 1
        sim.step(policy.act_sim(sim))
    return checked


def test_kept_nearest_origins_under_lorr_reassignment() -> None:
    """LoRR's rules: held slots leave the queue, released ones come back, a task
    changes hands; the kept nearest origins stay equal to fresh ones."""
    from rtaw_marl.policies.pairs import PairGreedy
    from rtaw_marl.scenarios.lorr import lorr_scenario

    spec = lorr_scenario("builtin:random_32_32_20_100.json", horizon=40).spec()
    sim = build_sim(spec)
    assert _check_along_episode(sim, 2, PairGreedy()) > 100
    assert sim.executor.stats()["reassigned"] > 0


@pytest.mark.parametrize("navigator", ["direct", "astar"])
@pytest.mark.parametrize("mode", ["drain", "paper"])
def test_kept_distances_equal_fresh_ones(navigator: str, mode: str) -> None:
    sim = _sim(navigator, episode_mode=mode)
    # Two episodes on one simulator: a reset must forget the first one's matrices.
    assert _check_along_episode(sim, 3) == 60
    assert _check_along_episode(sim, 4) == 60


def test_kept_distances_with_cell_slots(monkeypatch: pytest.MonkeyPatch) -> None:
    """Large pools keep cells, not fields (another ``TargetSlots``): same contract."""
    monkeypatch.setattr(distances, "SLOT_FIELDS_BYTES", 0)
    sim = _sim("astar")
    assert type(sim._slots).__name__ == "_CellSlots"
    assert _check_along_episode(sim, 5) == 60


def test_kept_distances_after_a_loaded_state() -> None:
    """A loaded state replaces every robot and slot: nothing of the old one is kept."""
    source, target = _sim("astar"), _sim("astar")
    source.reset(1)
    target.reset(2)
    for _ in range(9):
        source.step(int(np.flatnonzero(source.queue_mask)[0]))
    target.distance_matrix(), target.chain_nearest()  # fill target's cache
    target.load_state(source.state())
    every = np.arange(target.queue_len)
    np.testing.assert_array_equal(target.distance_matrix(), source.distance_matrix(every))
    np.testing.assert_array_equal(target.chain_nearest(), source.chain_nearest(every))
    np.testing.assert_array_equal(target.chain_nearest(every), _fresh_nearest(source, every))


@pytest.mark.parametrize("cell_slots", [False, True])
def test_kept_distances_across_loads_of_nearby_states(
    cell_slots: bool, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A mirror loaded again and again with an outside episode's states (deciding in
    between, as LoRR's adapter does) refreshes only what each load changed, and its kept
    distances equal fresh ones after every load."""
    if cell_slots:
        monkeypatch.setattr(distances, "SLOT_FIELDS_BYTES", 0)
    source, mirror = _sim("astar"), _sim("astar")
    source.reset(1)
    mirror.reset(2)
    every = np.arange(mirror.queue_len)
    for i in range(40):
        source.step(int(np.flatnonzero(source.queue_mask)[0]))
        if i % 3:
            continue
        mirror.load_state(source.state())
        np.testing.assert_array_equal(mirror.distance_matrix(), source.distance_matrix(every))
        np.testing.assert_array_equal(mirror.chain_nearest(), source.chain_nearest(every))
        np.testing.assert_array_equal(mirror.chain_nearest(every), _fresh_nearest(source, every))
        mirror.step(int(np.flatnonzero(mirror.queue_mask)[-1]))  # the mirror decides
        mirror.distance_matrix(), mirror.chain_nearest(every)  # and keeps what it saw


def test_a_caller_writing_the_returned_matrix_does_not_change_the_next_one() -> None:
    sim = _sim("direct")
    sim.reset(0)
    first = sim.distance_matrix()
    first[:] = -1.0
    assert (sim.distance_matrix() >= 0).all()


def test_nearest_other_origin_skips_own_and_empty_slots() -> None:
    chain = np.array([[0.0, 4.0, 1.0], [2.0, 0.0, 9.0], [3.0, 5.0, 0.0]])
    out = np.empty(3)
    nearest_other_origin(chain, np.array([True, True, False]), out)
    # Slot 0's nearest other is slot 1 (slot 2 is empty); slot 2 is empty: inf.
    np.testing.assert_array_equal(out, [4.0, 2.0, np.inf])
    nearest_other_origin(chain, np.array([True, False, False]), out)
    np.testing.assert_array_equal(out, [np.inf, np.inf, np.inf])
