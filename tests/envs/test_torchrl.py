"""The batched TorchRL env: specs, auto-reset, and the same trajectories as the AEC env."""

from __future__ import annotations

import numpy as np
import pytest
import torch
from tensordict import TensorDictBase
from torchrl.collectors import Collector
from torchrl.envs.utils import check_env_specs

from rtaw_marl import warehouse_v1
from rtaw_marl.envs.torchrl import BatchedWarehouseEnv
from rtaw_marl.errors import ConfigError, InvalidActionError
from rtaw_marl.sim.builder import SimSpec

pytestmark = pytest.mark.unit

SMALL = {"num_robots": 4, "num_tasks": 12, "queue_len": 3}


def _env(num_envs: int = 3, seed: int = 0, **sim) -> BatchedWarehouseEnv:
    return BatchedWarehouseEnv(
        SimSpec.of({**SMALL, **sim}, {"name": "open", "width": 12, "height": 9}, "astar", "random"),
        num_envs=num_envs,
        seed=seed,
    )


@pytest.mark.parametrize("mode", ["drain", "paper"])
def test_check_env_specs(mode: str) -> None:
    check_env_specs(_env(episode_mode=mode))


@pytest.mark.parametrize(
    ("layout", "navigator", "tasks", "mode"),
    [
        ({"name": "open", "width": 12, "height": 9}, "direct", "random", "drain"),
        ("shelves", "astar", "designated", "paper"),
    ],
)
def test_same_trajectory_as_aec_env(layout, navigator: str, tasks: str, mode: str) -> None:
    """Same seed and same actions: bit-identical observations, rewards and TTD."""
    env_cfg = {"num_robots": 5, "num_tasks": 25, "queue_len": 4, "episode_mode": mode}
    batched = BatchedWarehouseEnv(SimSpec.of(env_cfg, layout, navigator, tasks), num_envs=2, seed=3)
    td = batched.reset()
    rng = np.random.default_rng(0)
    aecs = []
    for b in range(2):
        aec = warehouse_v1.raw_env(**env_cfg, layout=layout, navigator=navigator, tasks=tasks)
        aec.reset(seed=int(batched.episode_seeds[b]))
        aecs.append(aec)
    for _ in range(env_cfg["num_tasks"]):
        actions = []
        for b, aec in enumerate(aecs):
            obs = aec.observe(aec.agent_selection)
            for key in ("robots", "tasks", "agent", "relations", "rivals"):
                np.testing.assert_array_equal(obs["observation"][key], td[key][b].numpy())
            np.testing.assert_array_equal(obs["action_mask"].astype(bool), td["action_mask"][b])
            actions.append(int(rng.choice(np.flatnonzero(obs["action_mask"]))))
        td["action"] = torch.tensor(actions)
        out = batched.step(td)
        for b, aec in enumerate(aecs):
            agent = aec.agent_selection
            aec.step(actions[b])
            assert out["next", "reward"][b, 0].item() == pytest.approx(aec.rewards[agent], abs=1e-4)
        td = out["next"]
    for b, aec in enumerate(aecs):
        info = aec.infos[aec.agent_selection]
        assert batched.sims[b].metrics().ttd == info["ttd"]
        assert bool(td["done"][b])
        assert bool(td["truncated"][b]) == (mode == "paper")


def _masked_random(td: TensorDictBase) -> TensorDictBase:
    td["action"] = torch.multinomial(td["action_mask"].float(), 1).squeeze(-1)
    return td


def test_collector_resets_finished_episodes() -> None:
    """A collector runs across episode ends; finished simulators restart with new seeds."""
    env = _env(num_envs=2, num_tasks=5)
    first = env.episode_seeds.copy()
    collector = Collector(
        env,
        _masked_random,
        frames_per_batch=24,
        total_frames=24,
        auto_register_policy_transforms=False,
    )
    data = next(iter(collector))
    collector.shutdown()
    assert data.shape == (2, 12)
    assert data["next", "done"].sum() == 4  # 12 steps of 5-decision episodes: 2 ends each
    assert not np.array_equal(first, env.episode_seeds)
    assert data["action_mask"].gather(-1, data["action"].unsqueeze(-1)).all()


def test_action_spec_is_masked() -> None:
    """Random actions drawn from the env's action spec are always valid slots."""
    env = _env(num_envs=4, num_tasks=6, queue_len=5)  # drain: slots empty out at the end
    td = env.reset()
    for _ in range(6):
        td["action"] = env.action_spec.rand()
        assert td["action_mask"].gather(-1, td["action"].unsqueeze(-1)).all()
        td = env.step(td)["next"]


def test_seeded_env_is_deterministic() -> None:
    a, b = _env(seed=11), _env(seed=11)
    torch.manual_seed(0)
    ra = a.rollout(20, break_when_any_done=False)
    torch.manual_seed(0)
    rb = b.rollout(20, break_when_any_done=False)
    assert (ra == rb).all()


def test_reset_to_replays_explicit_seeds() -> None:
    env = _env(num_envs=2)
    td1 = env.reset_to([5, 6])
    td2 = env.reset_to([5, 6])
    assert (td1 == td2).all()
    assert env.episode_seeds.tolist() == [5, 6]


def test_invalid_action_raises() -> None:
    env = _env(num_envs=1)
    td = env.reset()
    td["action"] = torch.tensor([7])
    with pytest.raises(InvalidActionError):
        env.step(td)


@pytest.mark.parametrize(
    ("action", "match"),
    [
        (torch.tensor([0.0, 1.0, 0.0]), "integer tensor, got torch.float32"),
        (torch.tensor([True, False, True]), "integer tensor, got torch.bool"),
        (torch.tensor([0, 1, 4]), r"simulator 2: action 4 is not a queue slot \(0..3\)"),
        (torch.tensor([0, -1, 0]), "simulator 1: action -1 is not a queue slot"),
        (torch.tensor([0, 2, 0]), "simulator 1: action 2 names an empty queue slot"),
    ],
)
def test_bad_batched_action_raises_before_any_simulator_steps(
    action: torch.Tensor, match: str
) -> None:
    """A float, bool, out-of-range or empty slot anywhere in the batch fails at once, with
    the simulator named, and no simulator has stepped (slots 2 and 3 start empty)."""
    env = _env(num_envs=3, num_tasks=2, queue_len=4)
    td = env.reset()
    assert td["action_mask"][:, 2:].sum() == 0
    td["action"] = action
    with pytest.raises(InvalidActionError, match=match):
        env.step(td)
    assert [sim.decisions for sim in env.sims] == [0, 0, 0]
    td["action"] = torch.tensor([0, 1, 0])
    env.step(td)
    assert [sim.decisions for sim in env.sims] == [1, 1, 1]


@pytest.mark.parametrize("seed", [-1, 1.5, True])
def test_bad_seeds_raise_config_errors(seed: object) -> None:
    env = _env(num_envs=2)
    with pytest.raises(ConfigError, match="seed must be an integer >= 0"):
        env.reset_to([0, seed])
    with pytest.raises(ConfigError, match="seed must be an integer >= 0"):
        _env(num_envs=1, seed=seed)


def test_candidates_hold_the_nearest_tasks_and_map_actions_to_slots() -> None:
    """``candidates=K``: each decision's K nearest queued tasks, bit for bit the
    observation a ``NetworkPolicy(candidates=K)`` scores, the action an index into them;
    specs of width K; an index past K or on an empty candidate is refused."""
    from rtaw_marl.decision.features import FEATURES, candidate_slots, sim_observation

    spec = SimSpec.of(
        {"num_robots": 6, "num_tasks": 60, "queue_len": 12}, "shelves", "astar", "random"
    )
    env = BatchedWarehouseEnv(spec, num_envs=2, seed=5, candidates=4)
    check_env_specs(env)
    assert env.observation_spec["relations"].shape == (2, 4, 8)
    td = env.reset()
    rng = np.random.default_rng(1)
    for _ in range(40):
        picks = []
        for b, sim in enumerate(env.sims):
            key = (sim.robot_distances() / sim.layout.scale).astype(np.float32)
            slots = candidate_slots(key, sim.queue_mask, 4)
            np.testing.assert_array_equal(env.candidate_slots[b], slots)
            want = sim_observation(sim, FEATURES, slots)
            for name in FEATURES:
                np.testing.assert_array_equal(td[name][b].numpy(), want[name])
            np.testing.assert_array_equal(td["action_mask"][b].numpy(), want["action_mask"])
            picks.append(int(rng.choice(np.flatnonzero(want["action_mask"]))))
        chosen = [int(env.candidate_slots[b, a]) for b, a in enumerate(picks)]
        ids = [int(sim.queue_ids[s]) for sim, s in zip(env.sims, chosen, strict=True)]
        td["action"] = torch.tensor(picks)
        td = env.step(td)["next"]
        for sim, task in zip(env.sims, ids, strict=True):
            assert sim.done or sim.task_assigned[task] >= 0
    td["action"] = torch.tensor([4, 0])
    with pytest.raises(InvalidActionError, match="simulator 0: action 4 is not a candidate"):
        env.step(td)
    with pytest.raises(ConfigError, match="candidates must be an integer >= 1"):
        BatchedWarehouseEnv(spec, num_envs=1, candidates=0)
