"""The relational features (``relations``, ``rivals``) against a plain-Python oracle."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from rtaw_marl import warehouse_v1
from rtaw_marl.decision.features import MISSING, NUM_RIVALS, SOFTMIN_TEMPERATURE
from tests.envs.test_pettingzoo import first_valid, is_done, oracle_distance

pytestmark = pytest.mark.unit


def _oracle(sim, robot: int, navigator: str) -> tuple[np.ndarray, np.ndarray]:
    """Relations and rivals of ``robot``'s view, one task and one robot at a time."""
    scale = sim.layout.scale
    n, m = sim.queue_len, sim.num_robots
    relations = np.zeros((n, 8))
    rivals = np.zeros((n, NUM_RIVALS, 4))
    for i in range(n):
        if not sim.queue_mask[i]:
            continue
        ox, oy, dx, dy = sim.tasks[sim.queue_ids[i]]
        arrival = {}
        for j in range(m):
            wait = max(sim.robot_free_at[j] - sim.time, 0.0)
            dist = float(oracle_distance(navigator, sim.robot_xy[j], np.array([[ox, oy]]))[0])
            arrival[j] = (wait + dist, wait, dist)
        own = arrival[robot][0]
        others = sorted((arrival[j][0] - own, j) for j in range(m) if j != robot)
        deltas = [d for d, _ in others]
        top = (deltas + [MISSING * scale] * 3)[:3]
        t = SOFTMIN_TEMPERATURE * scale
        near = deltas[:NUM_RIVALS]
        softmin = -t * math.log(sum(math.exp(-d / t) for d in near)) if near else MISSING * scale
        chain = [
            float(
                oracle_distance(navigator, np.array([dx, dy]), sim.tasks[[sim.queue_ids[k]], :2])[0]
            )
            for k in range(n)
            if k != i and sim.queue_mask[k]
        ]
        wait_q = sim.time - sim.task_arrival[sim.queue_ids[i]]
        relations[i] = [own, sim.queue_length[i], wait_q, *top, softmin,
                        min(chain) if chain else MISSING * scale]  # fmt: skip
        relations[i] /= scale
        for r, (d, j) in enumerate(others[:NUM_RIVALS]):
            rivals[i, r] = [d / scale, arrival[j][1] / scale, arrival[j][2] / scale, 1.0]
    return relations, rivals


@pytest.mark.parametrize(("navigator", "robots"), [("astar", 5), ("direct", 12), ("astar", 1)])
def test_relational_features_match_oracle(navigator: str, robots: int) -> None:
    """Every agent's view at every decision of a drain episode (empty slots at the end)."""
    env = warehouse_v1.env(
        num_robots=robots,
        queue_len=4,
        num_tasks=20,
        layout={"name": "open", "width": 17, "height": 11},
        navigator=navigator,
        tasks="random",
    )
    env.reset(seed=3)
    sim = env.unwrapped.sim
    checked = 0
    while not is_done(env):
        for i, agent in enumerate(env.agents):
            features = env.observe(agent)["observation"]
            relations, rivals = _oracle(sim, i, navigator)
            np.testing.assert_allclose(features["relations"], relations, rtol=1e-5, atol=1e-5)
            np.testing.assert_allclose(features["rivals"], rivals, rtol=1e-5, atol=1e-5)
            checked += 1
        obs, *_ = env.last()
        env.step(first_valid(obs))
    assert checked == 20 * robots


# --------------------------------------------------------------------------- fast paths
def test_compiled_rivals_equal_a_stable_sort_of_every_robot() -> None:
    """The acting robot's rivals (compiled, one pass over the fleet) are the first ``k``
    of a stable sort of ``arrival - own`` over all other robots: ties (integer grid
    distances, many robots free now) go to the lowest robot id, at the k-th place too."""
    from rtaw_marl.decision.relational import _actor_rivals

    rng = np.random.default_rng(0)
    for _ in range(300):
        p, m, n = int(rng.integers(1, 4)), int(rng.integers(2, 40)), int(rng.integers(1, 12))
        dist = rng.integers(0, 20, (p, m, n)).astype(float)
        rem = np.where(rng.random((p, m)) < 0.3, 0.0, rng.integers(0, 10, (p, m)) * 0.5)
        actor = rng.integers(0, m, p)
        rem[np.arange(p), actor] = 0.0
        k = min(NUM_RIVALS, m - 1)
        order, delta = _actor_rivals(dist, rem, actor, k)
        for i in range(p):
            for t in range(n):
                d = (dist[i, :, t] + rem[i]) - (dist[i, actor[i], t] + rem[i, actor[i]])
                d[actor[i]] = np.inf
                want = np.argsort(d, kind="stable")[:k]
                assert order[i, 0, t].tolist() == want.tolist()
                assert delta[i, 0, t].tolist() == d[want].tolist()


@pytest.mark.parametrize("m", [1, 2, 7, 1000])
def test_fleet_summary_is_quantiles_and_mean_of_the_times_until_free(m: int) -> None:
    from rtaw_marl.decision.features import FLEET_QUANTILES, fleet_features

    rng = np.random.default_rng(m)
    free_at = rng.random((3, m)) * 50.0
    time = np.array([0.0, 10.0, 60.0])
    got = fleet_features(free_at, time, 60.0)
    assert got.shape == (3, 8)
    assert got.dtype == np.float32
    for b in range(3):
        remaining = np.sort(np.maximum(free_at[b] - time[b], 0.0))
        want = [remaining[round(q * (m - 1))] / 60.0 for q in FLEET_QUANTILES]
        np.testing.assert_allclose(got[b, :-1], want, rtol=1e-6)
        np.testing.assert_allclose(got[b, -1], remaining.mean() / 60.0, rtol=1e-6)
    assert not got[2].any()  # everyone free at t = 60


@pytest.mark.parametrize(("robots", "navigator"), [(1, "direct"), (5, "astar"), (40, "direct")])
def test_compiled_acting_view_equals_the_numpy_functions(robots: int, navigator: str) -> None:
    """The acting view (compiled, every env step) equals the NumPy functions' values bit
    for bit: one simulator and the same decisions stacked as a batch."""
    from rtaw_marl.decision.features import (
        ALL_KEYS,
        Decision,
        decision_features,
        fleet_features,
        relational_features,
        robot_features,
        task_features,
    )

    env = warehouse_v1.env(num_robots=robots, num_tasks=60, navigator=navigator, tasks="random")
    env.reset(seed=11)
    sim = env.unwrapped.sim
    decisions = []
    while not sim.done and len(decisions) < 25:
        d = Decision.of_sim(sim, ALL_KEYS)
        got = decision_features(d, ALL_KEYS)
        rows = robot_features(d.robot_xy, d.free_at, d.time, d.scale)
        remaining = d.free_at - d.time
        rel, rivals = relational_features(
            d.distances, remaining, np.array([d.robot]), d.queue_length, d.waits, d.nearest,
            d.queue_mask, d.scale,
        )  # fmt: skip
        want = {
            "robots": rows,
            "agent": rows[d.robot],
            "tasks": task_features(
                d.queue_rows, d.queue_length, d.own_distances, d.queue_mask, d.scale
            ),
            "fleet": fleet_features(d.free_at, d.time, d.scale),
            "relations": rel[0],
            "rivals": rivals[0],
            "action_mask": d.queue_mask,
        }
        assert set(got) == set(want)
        for key, value in want.items():
            assert got[key].dtype == value.dtype, key
            assert got[key].tobytes() == value.tobytes(), key
        # The simulator's arrays change in place: keep this decision's values.
        kept = {f.name: np.copy(getattr(d, f.name)) for f in dataclasses.fields(d)}
        decisions.append((Decision(**kept), got))
        sim.step(int(np.flatnonzero(sim.queue_mask)[0]))
    stacked = Decision(
        *(np.stack([getattr(d, f) for d, _ in decisions]) for f in (
            "robot_xy", "free_at", "time", "robot", "queue_rows", "queue_length", "queue_mask")),
        decisions[0][0].scale,
        **{f: np.stack([getattr(d, f) for d, _ in decisions])
           for f in ("own_distances", "distances", "waits", "nearest")},
    )  # fmt: skip
    batch = decision_features(stacked, ALL_KEYS)
    for key in ALL_KEYS:
        want = np.stack([got[key] for _, got in decisions])
        assert batch[key].tobytes() == want.tobytes(), key


def test_compiled_hypot_equals_numpy_on_every_grid_difference() -> None:
    """The slot kernels' ``math.hypot`` is ``np.hypot`` on every integer difference of a
    grid up to 1,100 cells wide, so compiled and NumPy distances agree bit for bit."""
    from rtaw_marl.sim._slot_kernels import euclidean_from

    r = np.arange(-1100, 1101)
    xy = np.stack(np.meshgrid(r, [0]), -1).reshape(-1, 2)  # [P, 2]: (dx, 0)
    targets = np.stack([np.zeros(len(r)), -r.astype(np.float64)], -1)  # [K, 2]: (0, -dy)
    out = np.empty((len(xy), len(targets)))
    euclidean_from(xy, targets, out)
    assert out.tobytes() == np.hypot(r[:, None].astype(np.float64), r[None, :]).tobytes()


@pytest.mark.parametrize("navigator", ["direct", "astar"])
@pytest.mark.parametrize(
    "keys", [("robots", "tasks", "agent", "relations", "rivals", "fleet"), ("relations", "rivals")]
)
def test_observation_read_from_the_simulator_equals_the_decision_path(
    navigator: str, keys: tuple[str, ...]
) -> None:
    """``sim_observation`` (every env step: read straight from the simulator, its kept
    distances uncopied) equals ``decision_features`` of ``Decision.of_sim``."""
    from rtaw_marl.decision.features import Decision, decision_features, sim_observation

    env = warehouse_v1.env(num_robots=12, num_tasks=50, navigator=navigator, tasks="random")
    env.reset(seed=5)
    sim = env.unwrapped.sim
    steps = 0
    while not sim.done:
        got = sim_observation(sim, keys)
        want = decision_features(Decision.of_sim(sim, keys), keys)
        assert set(got) == set(want) == {*keys, "action_mask"}
        for key, value in want.items():
            assert got[key].tobytes() == value.tobytes(), key
        sim.step(int(np.flatnonzero(sim.queue_mask)[-1]))
        steps += 1
    assert steps == 50
