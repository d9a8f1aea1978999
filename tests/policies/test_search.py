"""Search with a learned policy (policy=search): its rollouts, its options, its honesty."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from rtaw_marl.errors import ConfigError
from rtaw_marl.policies import make_baseline
from rtaw_marl.policies.config import SearchConfig
from rtaw_marl.policies.lookahead import lookahead_costs, rollout_distances
from rtaw_marl.policies.network import NetworkPolicy, load_policy
from rtaw_marl.policies.search import Rollout, nearest_scores, search_costs, top_slots
from rtaw_marl.policies.search_policy import SearchPolicy, load_search
from rtaw_marl.sim.builder import SimSpec, build_sim
from rtaw_marl.sim.core import WarehouseSim

pytestmark = pytest.mark.unit

#: A small shipped RTAW+ and the paper's network (both kinds of inputs).
PLUS, PAPER = "shelves_astar_m10_plus", "shelves_astar_m10"


def _sim(**keys: object) -> WarehouseSim:
    sim = build_sim(SimSpec.of({"num_tasks": 120, **keys}))
    sim.reset(seed=1000)
    return sim


def _rollout(sim: WarehouseSim) -> Rollout:
    rows, mask = sim.queue_rows, sim.queue_mask
    return Rollout(
        robot=int(sim.robot), now=float(sim.time), robot_xy=sim.robot_xy,
        free_at=sim.robot_free_at, rows=rows, lengths=sim.queue_length, mask=mask,
        waits=sim.queue_waits(),
        ends=rollout_distances(sim.distance_model, sim.robot_xy, rows, mask),
        noise_mean=float(sim.config.noise_mean), scale=float(sim.layout.scale),
    )  # fmt: skip


@pytest.mark.parametrize("keys", [("relations",), ("tasks",)])
@pytest.mark.parametrize("horizon", [0, 1, 3, 8])
def test_rollout_with_the_nearest_task_is_lookahead(keys: tuple[str, ...], horizon: int) -> None:
    """With MPDM choosing in the rollouts, the search's costs are lookahead's, decision
    after decision (which checks the rollout's state: free times, cells, queue)."""
    sim, mpdm = _sim(), make_baseline("mpdm")
    checked = 0
    while not sim.done:
        state, mask = _rollout(sim), sim.queue_mask
        lengths = np.where(mask, sim.queue_length, 0.0)
        want = lookahead_costs(
            state.ends[sim.robot], state.ends, sim.robot, sim.robot_free_at, sim.time,
            lengths, mask, horizon, sim.config.noise_mean,
        )  # fmt: skip
        slots = np.flatnonzero(mask)
        got = search_costs(state, slots, horizon, nearest_scores, keys)
        np.testing.assert_allclose(got, want[slots])
        checked += 1
        sim.step(mpdm.act_sim(sim))
    assert checked == 120


def test_leaf_value_is_subtracted_from_each_rollout() -> None:
    sim = _sim()
    state, slots = _rollout(sim), np.flatnonzero(sim.queue_mask)
    plain = search_costs(state, slots, 2, nearest_scores, ("relations",))
    seen: list[int] = []

    def leaf(features: dict[str, np.ndarray]) -> np.ndarray:
        seen.append(features["relations"].shape[0])
        return np.arange(len(slots), dtype=np.float64)

    valued = search_costs(state, slots, 2, nearest_scores, ("relations",), leaf)
    np.testing.assert_allclose(valued, plain - np.arange(len(slots)))
    assert seen == [len(slots)]  # one batched call, at the rollouts' final states


def test_top_slots_are_the_best_queued_scores_in_order() -> None:
    scores = np.array([0.5, 3.0, 3.0, -1.0, 9.0])
    mask = np.array([True, True, True, True, False])
    assert top_slots(scores, mask, 3).tolist() == [1, 2, 0]
    assert top_slots(scores, mask, 10).tolist() == [1, 2, 0, 3]


@pytest.mark.parametrize("source", [PLUS, PAPER])
def test_width_one_is_the_network_alone(source: str) -> None:
    network = load_policy(source)
    search = load_search(source, width=1, horizon=3)
    sim = _sim()
    while not sim.done:
        slot = network.act_sim(sim)
        assert search.act_sim(sim) == slot
        sim.step(slot)


def test_batched_scores_match_the_eager_network() -> None:
    """The traced batched call gives the eager logits at any batch size and queue length."""
    search = load_search(PLUS)
    rng = np.random.default_rng(0)
    for b, n in [(1, 10), (4, 10), (3, 50), (8, 7)]:
        features = {
            "relations": rng.random((b, n, 8), dtype=np.float32),
            "rivals": rng.random((b, n, 8, 4), dtype=np.float32),
            "action_mask": rng.random((b, n)) > 0.2,
        }
        with torch.no_grad():
            eager = search.network.net(
                *(torch.from_numpy(features[k]) for k in ("relations", "rivals")),
                torch.from_numpy(features["action_mask"]),
            )
        np.testing.assert_array_equal(search._scores(features), eager.double().numpy())


def test_search_sees_no_future() -> None:
    """The decision depends on the current state only: changing the tasks not yet
    revealed and the noise generator changes nothing, and the simulator is not moved."""
    search = load_search(PLUS, width=4, horizon=3)
    sim = _sim()
    for _ in range(30):
        sim.step(search.act_sim(sim))
    before = sim.state()
    slot = search.act_sim(sim)
    after = sim.state()
    assert before.scalars == after.scalars
    assert before.arrays.keys() == after.arrays.keys()
    for key, array in before.arrays.items():
        assert np.array_equal(array, after.arrays[key], equal_nan=True), key
    hidden = slice(sim._next_task, None)
    sim.tasks[hidden] = sim.tasks[hidden][::-1].copy()
    assert search.act_sim(sim) == slot


def test_search_is_deterministic_and_differs_from_the_network() -> None:
    def episode(policy: object) -> list[int]:
        sim, slots = _sim(), []
        while not sim.done:
            slots.append(policy.act_sim(sim))  # type: ignore[attr-defined]
            sim.step(slots[-1])
        return slots

    a, b = episode(load_search(PLUS)), episode(load_search(PLUS))
    assert a == b
    assert a != episode(load_policy(PLUS))


def test_leaf_needs_the_critic_and_act_needs_the_simulator() -> None:
    network = NetworkPolicy(load_policy(PLUS).net)
    with pytest.raises(ValueError, match="critic"):
        SearchPolicy(network, leaf=1.0)
    with pytest.raises(NotImplementedError, match="act_sim"):
        SearchPolicy(network).act({})
    valued = load_search(PLUS, leaf=0.5)
    assert valued.critic is not None
    sim = _sim()
    assert sim.queue_mask[valued.act_sim(sim)]


@pytest.mark.parametrize(
    ("keys", "match"),
    [
        ({"width": 0}, "search.width must be an integer >= 1"),
        ({"width": True}, "search.width"),
        ({"horizon": -1}, "search.horizon must be an integer >= 0"),
        ({"leaf": -0.5}, "search.leaf must be a number >= 0"),
        ({"leaf": float("nan")}, "search.leaf"),
        ({"leaf": "1"}, "search.leaf"),
        ({"depth": 3}, "depth"),
    ],
)
def test_bad_search_options_are_refused(keys: dict, match: str) -> None:
    with pytest.raises((ConfigError, TypeError), match=match):
        SearchConfig(**keys)
    if "depth" not in keys:
        with pytest.raises(ConfigError, match=match):
            load_search(PLUS, **keys)


def test_a_proposing_rules_choice_is_tried_too() -> None:
    """``propose``: with width 1 the network's slot and hungarian's are rolled out; the
    choice is one of the two, and differs from the network alone somewhere."""
    search = load_search(PLUS, width=1, horizon=3, propose="hungarian")
    network, hungarian = load_policy(PLUS), make_baseline("hungarian")
    sim, differs = _sim(), 0
    search.reset(0)
    while not sim.done:
        slot = search.act_sim(sim)
        assert slot in (network.act_sim(sim), hungarian.act_sim(sim))
        differs += slot != network.act_sim(sim)
        sim.step(slot)
    assert differs > 0
    with pytest.raises(ConfigError, match=r"search\.propose: 'hindsight' is not a rule"):
        SearchConfig(propose=["mpdm", "hindsight"])


def test_with_candidates_the_search_stays_among_the_nearest_k() -> None:
    """``candidates=K`` on a long queue: the searched slot is one of the K tasks nearest
    the free robot (the network's candidates), and the episode plays through."""
    from rtaw_marl.decision.features import candidate_slots

    search = load_search(PLUS, candidates=4)
    sim = _sim(queue_len=12)
    while not sim.done:
        slot = search.act_sim(sim)
        if sim.queue_mask.sum() > 4:
            key = (sim.robot_distances() / sim.layout.scale).astype(np.float32)
            assert slot in candidate_slots(key, sim.queue_mask, 4)
        assert sim.queue_mask[slot]
        sim.step(slot)
