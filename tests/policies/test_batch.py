"""The ``batch`` rule: min-cost matching of the robots free now, with a region cap."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from rtaw_marl.errors import ConfigError
from rtaw_marl.policies import BaselinesConfig, make_baseline
from rtaw_marl.policies.batch import capped_costs, match
from rtaw_marl.sim.config import SimConfig
from rtaw_marl.sim.core import WarehouseSim
from rtaw_marl.sim.distances import GridDistance
from rtaw_marl.sim.layout import open_grid
from rtaw_marl.sim.tasks import FixedTasks

pytestmark = pytest.mark.unit


def brute_force(cost: np.ndarray) -> tuple[float, tuple[int, ...]]:
    """The cheapest injective assignment of rows to columns, by enumeration."""
    r, c = cost.shape
    return min(
        (float(cost[np.arange(r), list(cols)].sum()), cols)
        for cols in itertools.permutations(range(c), r)
    )


@pytest.mark.parametrize("seed", range(30))
def test_match_is_the_brute_force_optimum(seed: int) -> None:
    rng = np.random.default_rng(seed)
    r = int(rng.integers(1, 5))
    cost = rng.integers(0, 20, size=(r, int(rng.integers(r, 6)))).astype(float)
    cols = match(cost)
    assert len(set(cols.tolist())) == r
    assert cost[np.arange(r), cols].sum() == brute_force(cost)[0]


def test_capped_costs_penalize_only_full_regions() -> None:
    dist = np.zeros((1, 3))
    origins = np.array([[0, 0], [9, 9], [20, 0]])
    heading = np.array([[1, 1], [2, 3], [17, 1]])  # two in region (0, 0), one in (2, 0)
    cost = capped_costs(dist, origins, heading, region=8, cap=2, penalty=5.0)
    assert cost.tolist() == [[5.0, 0.0, 0.0]]
    assert capped_costs(dist, origins, heading[:0], 8, 1, 5.0).tolist() == [[0.0, 0.0, 0.0]]


def line_sim() -> WarehouseSim:
    """Two robots free at t = 0 on a 10x1 corridor, at x = 5 and x = 8; tasks from x = 6
    and from x = 0. MPDM sends robot 0 to x = 6 (1 + 8 = 9 cells of pickup travel in
    all); the matching sends it to x = 0 (5 + 2 = 7)."""
    layout = open_grid(10, 1)
    config = SimConfig(num_robots=2, num_tasks=2, queue_len=2, noise_mean=0.0, noise_var=0.0,
                       robot_starts=((5, 0), (8, 0)))  # fmt: skip
    tasks = FixedTasks([(6, 0, 9, 0), (0, 0, 1, 0)])
    sim = WarehouseSim(config, layout, GridDistance(layout), tasks)
    sim.reset(0)
    return sim


def test_free_robots_are_matched_not_served_greedily() -> None:
    sim = line_sim()
    assert sim.robot == 0
    dist = sim.robot_distances_many(np.array([0, 1]), np.array([0, 1]))
    assert dist.tolist() == [[1.0, 5.0], [2.0, 8.0]]
    assert brute_force(dist)[1] == (1, 0)
    assert make_baseline("mpdm").act_sim(sim) == 0
    batch = make_baseline("batch")
    assert batch.act_sim(sim) == 1
    sim.step(1)
    assert batch.act_sim(sim) == 0  # robot 1 takes the rest


def test_parameters_and_the_observation_path() -> None:
    params = BaselinesConfig(batch_region=4, batch_cap=2, batch_penalty=3.0)
    rule = make_baseline("batch", params=params)
    assert (rule.region, rule.cap, rule.penalty) == (4, 2, 3.0)
    with pytest.raises(ConfigError, match=r"baselines\.batch_cap must be an integer >= 1"):
        BaselinesConfig(batch_cap=0)
    with pytest.raises(NotImplementedError, match="acts on the simulator only"):
        rule.act({})


def test_lookahead_on_k_candidates_is_lookahead_on_that_sub_queue() -> None:
    """lookahead_candidates=K: with K >= the queue it is lookahead itself; with fewer it
    picks among the K origins nearest the free robot."""
    from rtaw_marl.decision.features import candidate_slots
    from rtaw_marl.scenarios import SCENARIOS
    from rtaw_marl.sim.builder import build_sim

    sim = build_sim(SCENARIOS["C_astar_m10"].with_sim(queue_len=20, num_tasks=60).spec())
    full = make_baseline("lookahead")
    wide = make_baseline("lookahead", params=BaselinesConfig(lookahead_candidates=20))
    narrow = make_baseline("lookahead", params=BaselinesConfig(lookahead_candidates=5))
    sim.reset(2)
    while not sim.done:
        choice = full.act_sim(sim)
        assert wide.act_sim(sim) == choice
        if sim.queue_mask.sum() > 5:
            near = candidate_slots(sim.robot_distances(), sim.queue_mask, 5)
            assert narrow.act_sim(sim) in near.tolist()
        sim.step(choice)
    with pytest.raises(ConfigError, match=r"lookahead_candidates must be an integer >= 1"):
        BaselinesConfig(lookahead_candidates=0)


def test_a_fleet_freed_at_once_is_matched_in_chunks() -> None:
    """batch_max caps the robots of one matching: with one, the acting robot is matched
    alone (MPDM's choice on the corridor); with two, the pair is matched."""
    sim = line_sim()
    assert make_baseline("batch", params=BaselinesConfig(batch_max=1)).act_sim(sim) == 0
    assert make_baseline("batch", params=BaselinesConfig(batch_max=2)).act_sim(sim) == 1
