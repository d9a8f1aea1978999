"""A learned policy's decisions in batches (``rtaw_marl.policies.matched``): each free
robot scores the candidates its own decision would, one matching gives each robot and
task at most one partner, and episodes repeat for a seed."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from rtaw_marl.decision.features import candidate_slots, decision_features, sim_observation
from rtaw_marl.decision.schema import Decision
from rtaw_marl.errors import ConfigError
from rtaw_marl.policies.matched import MatchedPolicy, nearest_slots
from rtaw_marl.policies.network import NetworkPolicy, load_policy
from rtaw_marl.sim.core import WarehouseSim

pytestmark = pytest.mark.integration


def _sim(horizon: int = 120) -> WarehouseSim:
    from rtaw_marl.scenarios.lorr import lorr_scenario
    from rtaw_marl.sim.builder import build_sim

    return build_sim(lorr_scenario("builtin:random_32_32_20_100.json", horizon=horizon).spec())


@pytest.fixture(scope="module")
def network() -> NetworkPolicy:
    return load_policy("generalist_plus", candidates=16)


def test_each_robot_scores_the_candidates_of_its_own_decision(network: NetworkPolicy) -> None:
    """The acting robot's row is its own decision's: the same K slots, the same features
    bit for bit, the same log-probabilities (up to float rounding of a batched call)."""
    sim, policy = _sim(), MatchedPolicy(network)
    sim.reset(5)
    keys = frozenset(network.feature_keys)
    for _ in range(150):
        robots = sim.free_robots()
        slots, logp = policy.scores(sim, robots)
        me = int(np.searchsorted(robots, sim.robot))
        key = (sim.robot_distances() / sim.layout.scale).astype(np.float32)
        own = candidate_slots(key, sim.queue_mask, network.candidates)
        live = sim.queue_mask[own]
        np.testing.assert_array_equal(slots[me][slots[me] >= 0], own[live])
        alone = sim_observation(sim, keys, own)
        union, index = np.unique(slots, return_inverse=True)
        together = decision_features(
            Decision.of_sim(sim, keys, union), keys, robots, index.reshape(slots.shape)
        )
        for name in keys:
            np.testing.assert_array_equal(alone[name][live], together[name][me][live])
        inputs = [torch.from_numpy(alone[name]) for name in network.feature_keys]
        mask = torch.from_numpy(alone["action_mask"])
        with torch.no_grad():
            logits = torch.where(mask, network.net(*inputs, mask), -torch.inf)
        want = torch.log_softmax(logits, -1).numpy()[live]
        np.testing.assert_allclose(logp[me][slots[me] >= 0], want, rtol=1e-5, atol=1e-5)
        np.testing.assert_allclose(np.exp(logp).sum(axis=1), 1.0, rtol=1e-5)
        sim.step(network.act_sim(sim))


def test_the_matching_gives_each_robot_and_task_one_partner(network: NetworkPolicy) -> None:
    sim, policy = _sim(), MatchedPolicy(network)
    sim.reset(2)
    plan = policy.match(sim)  # t = 0: every robot is free
    tasks = [task for _, task in plan.values()]
    assert len(set(tasks)) == len(tasks)
    # A robot left out found every one of its candidates taken by another.
    robots = sim.free_robots()
    slots, _ = policy.scores(sim, robots)
    taken = {slot for slot, _ in plan.values()}
    left = [i for i, r in enumerate(robots.tolist()) if r not in plan]
    assert len(left) < sim.num_robots // 10
    assert all(set(slots[i][slots[i] >= 0].tolist()) <= taken for i in left)
    assert all(sim.queue_mask[slot] and sim.queue_ids[slot] == t for slot, t in plan.values())


def test_matched_episodes_repeat_and_use_the_plan(network: NetworkPolicy) -> None:
    """Every decision is legal, the plan serves most decisions (the rest decide alone),
    and a seed gives the same episode."""
    finished = []
    for _ in range(2):
        sim, policy = _sim(), MatchedPolicy(network)
        sim.reset(7)
        policy.reset(7)
        decisions = 0
        while not sim.done:
            slot = policy.act_sim(sim)
            assert sim.queue_mask[slot]
            decisions += 1
            sim.step(slot)
        assert policy.served + policy.alone == decisions
        assert policy.served > 0.8 * decisions
        finished.append((sim.metrics().tasks_finished, sim.task_robot.copy()))
    assert finished[0][0] == finished[1][0] > 0
    np.testing.assert_array_equal(finished[0][1], finished[1][1])


def test_matched_needs_candidates_and_the_simulator() -> None:
    with pytest.raises(ConfigError, match="candidates=K"):
        MatchedPolicy(load_policy("generalist_plus"))
    with pytest.raises(NotImplementedError, match="act_sim"):
        MatchedPolicy(load_policy("generalist_plus", candidates=8)).act({})


def test_views_over_columns_are_the_full_views_columns() -> None:
    """``decision_features(..., viewers, columns)``: each view's candidate rows, the same
    values as the full views' (every feature, the paper's ``tasks`` too)."""
    sim = _sim()
    sim.reset(3)
    for _ in range(40):
        sim.step(int(np.flatnonzero(sim.queue_mask)[0]))
    keys = frozenset({"relations", "rivals", "tasks", "agent", "fleet"})
    viewers = np.array([0, 5, 17, 42])
    rng = np.random.default_rng(0)
    columns = np.sort(rng.choice(sim.queue_len, size=(4, 12)), axis=1)
    decision = Decision.of_sim(sim, keys)
    full = decision_features(decision, keys, viewers)
    some = decision_features(decision, keys, viewers, columns)
    # The full views rank rivals once for all (equally early rivals may differ): the
    # rivals' arrivals, the relations and the paper's task rows are the same values.
    for name, cut in (("relations", slice(None)), ("rivals", 0), ("tasks", slice(None))):
        np.testing.assert_array_equal(some[name][..., cut], np.take_along_axis(
            full[name], columns.reshape(*columns.shape, *([1] * (full[name].ndim - 2))), 1
        )[..., cut])  # fmt: skip
    np.testing.assert_array_equal(some["action_mask"], sim.queue_mask[columns])
    np.testing.assert_array_equal(some["agent"], full["agent"])
    with pytest.raises(ValueError, match="columns need viewers"):
        decision_features(decision, keys, None, columns)


def test_nearest_slots_pick_what_candidate_slots_picks() -> None:
    rng = np.random.default_rng(1)
    key = rng.integers(0, 6, size=(50, 40)).astype(np.float32)  # many ties
    key[rng.random(key.shape) < 0.3] = np.inf  # empty slots
    for k in (1, 7, 39, 40, 60):
        got = nearest_slots(key, k)
        for row, want in zip(got, key, strict=True):
            np.testing.assert_array_equal(row, candidate_slots(want, np.isfinite(want), k))


def test_a_crowded_timestep_is_matched_a_batch_at_a_time(
    network: NetworkPolicy, monkeypatch: pytest.MonkeyPatch
) -> None:
    """At t = 0 every robot is free: each network call matches at most ``BATCH`` of
    them, the selected robot and the free robots nearest it; every robot is matched once
    per timestep, no task is promised twice, and the robots take their matches."""
    import rtaw_marl.policies.matched as matched

    monkeypatch.setattr(matched, "BATCH", 8)
    sim, policy = _sim(horizon=30), MatchedPolicy(network)
    calls: list[list[int]] = []
    promised: list[int] = []
    match = policy.match

    def spy(
        sim: WarehouseSim, robots: np.ndarray, exclude: np.ndarray | None = None
    ) -> dict[int, tuple[int, int]]:
        calls.append([sim.robot, *np.asarray(robots).tolist()])
        free = sim.free_robots()
        left = free[~policy._asked[free]]  # (the batch is marked asked already)
        gap = np.abs(sim.robot_xy - sim.robot_xy[sim.robot]).sum(axis=1)
        if len(left):
            assert gap[robots].max() <= gap[left].min()
        got = match(sim, robots, exclude)
        promised.extend(task for _, task in got.values())
        return got

    policy.match = spy  # type: ignore[method-assign]
    sim.reset(1)
    policy.reset(1)
    while sim.time == 0:
        slot = policy.act_sim(sim)
        assert sim.queue_mask[slot]
        sim.step(slot)
    assert len(calls) >= sim.num_robots // 8
    assert all(len(c) <= 9 and c[0] == c[1] for c in calls)  # the selected robot first
    matched_robots = [r for c in calls for r in c[1:]]
    assert len(matched_robots) == len(set(matched_robots)) == sim.num_robots
    assert len(promised) == len(set(promised))
    assert policy.served == len(promised) > 0.9 * sim.num_robots
