"""``candidates=K``: a learned policy scores only the ``K`` queued tasks nearest the free
robot, the same ``K`` on the observation path and the fast path."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from rtaw_marl import warehouse_v1
from rtaw_marl.decision.features import candidate_slots, nearest_other, sim_observation
from rtaw_marl.errors import ConfigError
from rtaw_marl.evaluation import run_episode
from rtaw_marl.sim.core import WarehouseSim

pytest.importorskip("torch")
from rtaw_marl.policies import load_policy

pytestmark = pytest.mark.unit

BIG: dict[str, Any] = {"num_robots": 30, "queue_len": 60, "num_tasks": 80, "layout": "C"}


def test_candidate_slots_are_the_k_nearest_non_empty_ties_to_the_lowest_slot() -> None:
    rng = np.random.default_rng(0)
    for _ in range(200):
        n, k = int(rng.integers(2, 40)), int(rng.integers(1, 12))
        dist = rng.integers(0, 6, n).astype(np.float32)  # many ties
        mask = rng.random(n) > 0.3
        got = candidate_slots(dist, mask, k)
        key = np.where(mask, dist, np.inf)
        expected = np.sort(np.lexsort((np.arange(n), key))[: min(k, n)])
        np.testing.assert_array_equal(got, expected)


def test_slot_subsets_equal_the_full_observation_rows() -> None:
    """``sim_observation(slots=...)`` holds the full observation's rows of these slots:
    rivals over the whole fleet, and each task's chain partner over the whole queue."""
    sim: WarehouseSim = warehouse_v1.env(navigator="astar", **BIG).unwrapped.sim
    sim.reset(3)
    keys = ("tasks", "relations", "rivals", "fleet")
    for _ in range(20):
        full = sim_observation(sim, keys)
        slots = np.sort(np.random.default_rng(sim.decisions).choice(60, 12, replace=False))
        part = sim_observation(sim, keys, slots)
        for key in ("tasks", "relations", "rivals", "action_mask"):
            np.testing.assert_array_equal(part[key], full[key][slots], err_msg=key)
        np.testing.assert_array_equal(part["fleet"], full["fleet"])
        sim.step(int(np.flatnonzero(sim.queue_mask)[0]))


def test_chain_nearest_is_the_nearest_other_origin() -> None:
    sim: WarehouseSim = warehouse_v1.env(navigator="astar", **BIG).unwrapped.sim
    sim.reset(0)
    np.testing.assert_array_equal(
        sim.chain_nearest(), nearest_other(sim.chain_distances(), sim.queue_mask)
    )


def _play_env(policy: Any, seed: int) -> tuple[list[int], float]:
    env = warehouse_v1.env(navigator="astar", **BIG)
    env.reset(seed=seed)
    actions: list[int] = []
    for _ in env.agent_iter():
        obs, _, terminated, truncated, info = env.last()
        action = None if terminated or truncated else policy.act(obs)
        if action is not None:
            actions.append(action)
        env.step(action)
    return actions, info["ttd"]


def _play_sim(policy: Any, seed: int) -> tuple[list[int], float, list[np.ndarray]]:
    sim: WarehouseSim = warehouse_v1.env(navigator="astar", **BIG).unwrapped.sim
    actions: list[int] = []
    nearest: list[np.ndarray] = []

    class Recorder:
        def reset(self, seed: int | None = None) -> None:
            policy.reset(seed)

        def act_sim(self, s: WarehouseSim) -> int:
            dist = np.where(s.queue_mask, s.robot_distances(), np.inf)
            nearest.append(np.sort(dist)[: policy.candidates or len(dist)])
            actions.append(policy.act_sim(s))
            chosen = dist[actions[-1]]
            assert policy.candidates is None or chosen <= nearest[-1][-1]
            return actions[-1]

    metrics = run_episode(sim, Recorder(), seed)
    return actions, metrics.ttd, nearest


@pytest.mark.parametrize("name", ["shelves_astar_m10_plus", "shelves_astar_m10"])
def test_both_paths_choose_the_same_slot_among_the_k_nearest(name: str) -> None:
    policy = load_policy(name, candidates=8)
    actions, ttd, _ = _play_sim(policy, 4)
    assert (actions, ttd) == _play_env(policy, 4)
    # Not the unrestricted policy's episode: the restriction changed some decisions.
    assert _play_sim(load_policy(name), 4)[0] != actions


def test_k_at_least_the_queue_is_the_unrestricted_policy() -> None:
    free = _play_sim(load_policy("shelves_astar_m10_plus"), 1)[:2]
    assert _play_sim(load_policy("shelves_astar_m10_plus", candidates=60), 1)[:2] == free


@pytest.mark.parametrize("bad", [0, -3, 2.5, True, "8"])
def test_bad_candidates_are_refused(bad: Any) -> None:
    with pytest.raises(ConfigError, match="candidates must be an integer >= 1"):
        load_policy("shelves_astar_m10_plus", candidates=bad)


def _observations(seed: int, count: int, **env_kwargs: Any) -> list[dict[str, Any]]:
    """``count`` acting robots' observations of one episode (copies)."""
    env = warehouse_v1.env(navigator="astar", **{**BIG, **env_kwargs})
    env.reset(seed=seed)
    kept: list[dict[str, Any]] = []
    for _ in env.agent_iter():
        obs, _, terminated, truncated, _ = env.last()
        if terminated or truncated or len(kept) == count:
            break
        features = obs["observation"]
        copied = (
            {k: np.array(v) for k, v in features.items()}
            if isinstance(features, dict)
            else np.array(features)
        )
        kept.append({"observation": copied, "action_mask": obs["action_mask"].copy()})
        env.step(int(np.flatnonzero(obs["action_mask"])[-1]))
    return kept


def _stack(observations: list[dict[str, Any]]) -> dict[str, Any]:
    first = observations[0]["observation"]
    features = (
        {k: np.stack([o["observation"][k] for o in observations]) for k in first}
        if isinstance(first, dict)
        else np.stack([o["observation"] for o in observations])
    )
    return {
        "observation": features,
        "action_mask": np.stack([o["action_mask"] for o in observations]),
    }


@pytest.mark.parametrize("name", ["shelves_astar_m10_plus", "shelves_astar_m10"])
@pytest.mark.parametrize(("candidates", "obs_format"), [(None, "dict"), (8, "dict"), (8, "flat")])
def test_act_batch_is_act_row_by_row(name: str, candidates: int | None, obs_format: str) -> None:
    """One network call for 40 decisions chooses what 40 calls of ``act`` choose."""
    policy = load_policy(name, candidates=candidates)
    observations = _observations(2, 40, obs_format=obs_format)
    got = policy.act_batch(_stack(observations))
    assert got.dtype == np.int64
    assert got.tolist() == [policy.act(o) for o in observations]
    if candidates is not None:  # every choice is among the K nearest queued origins
        for obs, slot in zip(observations, got, strict=True):
            features = obs["observation"]
            own = features["tasks"][:, 4] if isinstance(features, dict) else None
            if own is not None:
                key = np.where(obs["action_mask"] > 0, own, np.inf)
                assert key[slot] <= np.sort(key)[candidates - 1]


def test_act_batch_of_observe_all_acts_for_the_acting_robot_only() -> None:
    policy = load_policy("shelves_astar_m10_plus")
    env = warehouse_v1.env(navigator="astar", **BIG)
    env.reset(seed=0)
    env.step(0)
    everyone = env.unwrapped.observe_all()
    acting = env.unwrapped.sim.robot
    got = policy.act_batch(everyone)
    assert got[acting] == policy.act(env.observe(env.agent_selection))
    assert (np.delete(got, acting) == -1).all()


def test_act_batch_refuses_a_single_observation() -> None:
    policy = load_policy("shelves_astar_m10_plus")
    with pytest.raises(ConfigError, match=r"act_batch needs action_mask \[B, N\]"):
        policy.act_batch(_observations(0, 1)[0])


def test_act_batch_refuses_entries_of_other_batch_sizes() -> None:
    policy = load_policy("shelves_astar_m10_plus")
    stacked = _stack(_observations(0, 3))
    stacked["action_mask"] = stacked["action_mask"][:2]
    with pytest.raises(ConfigError, match=r"act_batch: relations has shape \(3, 60, 8\)"):
        policy.act_batch(stacked)
