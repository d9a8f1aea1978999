"""MixedBatchedEnv: simulators of several scenarios in one batch, each row exactly what a
lone batched env of its member gives, queues padded, rewards in units of L."""

from __future__ import annotations

import numpy as np
import pytest
import torch
from torchrl.envs.utils import check_env_specs

from rtaw_marl.envs.mixed import MixedBatchedEnv
from rtaw_marl.envs.torchrl import BatchedWarehouseEnv
from rtaw_marl.errors import ConfigError, InvalidActionError
from rtaw_marl.scenarios.mix import member_spec
from rtaw_marl.sim.inputs import RESERVED_SEEDS

pytestmark = pytest.mark.unit

#: Two fleets, two queue lengths, two navigators, both episode modes, short episodes.
SMALL = member_spec("open60_direct_m10:t20")
OTHER = member_spec("A_astar_m10:m3:n4:t12:paper")
KEYS = ("relations", "rivals", "fleet", "tasks", "agent")


def first_valid(td):
    td["action"] = td["action_mask"].int().argmax(-1)
    return td


def test_specs_and_shapes() -> None:
    env = MixedBatchedEnv([(SMALL, 2), (OTHER, 3)], seed=0, keys=KEYS)
    check_env_specs(env)
    td = env.reset()
    assert td.batch_size == torch.Size([5])
    assert td["relations"].shape == (5, 10, 8)
    assert td["rivals"].shape == (5, 10, 8, 4)
    assert td["fleet"].shape == (5, 8)
    assert env.offsets.tolist() == [0, 2, 5]
    assert len(env.sims) == 5


def test_rows_are_their_members_own_episodes() -> None:
    """Row by row, the mix gives what a lone batched env of the member gives on the same
    episode seeds: observations (queue padded), rewards divided by L, dones."""
    mixed = MixedBatchedEnv([(SMALL, 2), (OTHER, 3)], seed=3, keys=KEYS)
    td = mixed.reset()
    alone = [BatchedWarehouseEnv(spec, n, keys=KEYS) for spec, n in ((SMALL, 2), (OTHER, 3))]
    parts = [
        env.reset_to(mixed.episode_seeds[lo:hi].tolist())
        for env, lo, hi in zip(alone, mixed.offsets[:-1], mixed.offsets[1:], strict=True)
    ]
    for _ in range(15):  # past the end of OTHER's 12-decision episodes
        for key in (*KEYS, "action_mask"):
            lone = [p[key] for p in parts]
            assert torch.equal(td[key][:2], lone[0])
            assert torch.equal(td[key][2:, :4] if key in ("relations", "rivals", "tasks",
                                                           "action_mask") else td[key][2:],
                               lone[1])  # fmt: skip
        # OTHER's padded slots are empty.
        assert not td["action_mask"][2:, 4:].any()
        assert not td["relations"][2:, 4:].any()
        out = mixed.step(first_valid(td))
        nxt = [env.step(first_valid(p))["next"] for env, p in zip(alone, parts, strict=True)]
        scales = [env.scale for env in alone]
        want = torch.cat([n["reward"] / s for n, s in zip(nxt, scales, strict=True)])
        assert torch.equal(out["next", "reward"], want)
        assert torch.equal(out["next", "done"], torch.cat([n["done"] for n in nxt]))
        done = out["next", "done"]
        td = out["next"]
        if done.any():  # OTHER's episodes end first: only they restart
            assert done[2:].all()
            assert not done[:2].any()
            td = mixed.reset(td.clone().set("_reset", done.clone()))
            parts[1] = alone[1].reset_to(mixed.episode_seeds[2:].tolist())
            nxt[1] = parts[1]
        parts = [n.select(*KEYS, "action_mask") for n in nxt]
    assert min(mixed.episode_seeds) >= RESERVED_SEEDS


def test_misuse_is_one_clear_error() -> None:
    with pytest.raises(ConfigError, match=r"cannot stack observation key\(s\) \['robots'\]"):
        MixedBatchedEnv([(SMALL, 1)], keys=("robots",))
    with pytest.raises(ConfigError, match="at least one member"):
        MixedBatchedEnv([])
    with pytest.raises(ConfigError, match=">= 1 simulator"):
        MixedBatchedEnv([(SMALL, 0)])
    env = MixedBatchedEnv([(SMALL, 1), (OTHER, 1)], keys=KEYS)
    td = env.reset()
    td["action"] = torch.tensor([0, 7])  # slot 7 is padding for OTHER's queue of 4
    with pytest.raises(InvalidActionError, match=r"mix member 1 \(rows 1-1\): .*action 7"):
        env.step(td)


def test_seeded_mixes_repeat() -> None:
    def episode(seed: int) -> np.ndarray:
        env = MixedBatchedEnv([(SMALL, 2), (OTHER, 1)], seed=seed, keys=KEYS)
        td, rewards = env.reset(), []
        for _ in range(10):
            out = env.step(first_valid(td))
            rewards.append(out["next", "reward"].numpy().copy())
            td = out["next"]
        return np.concatenate(rewards)

    assert np.array_equal(episode(4), episode(4))
    assert not np.array_equal(episode(4), episode(5))
