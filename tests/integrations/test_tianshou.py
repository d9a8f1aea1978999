"""Tianshou's ``PettingZooEnv`` on ``warehouse_v1.env()`` as it is, no adapter: a masked
random policy per robot collects 1,000 steps through Tianshou's own ``Collector``."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

pytest.importorskip("tianshou")

from tianshou.algorithm.multiagent.marl import MultiAgentOffPolicyAlgorithm
from tianshou.algorithm.random import MARLRandomDiscreteMaskedOffPolicyAlgorithm
from tianshou.data import Collector, ReplayBuffer
from tianshou.env import DummyVectorEnv
from tianshou.env.pettingzoo_env import PettingZooEnv

from rtaw_marl import warehouse_v1

pytestmark = pytest.mark.integration

SMALL: dict[str, Any] = {
    "num_robots": 3,
    "queue_len": 4,
    "num_tasks": 40,
    "layout": {"name": "open", "width": 12, "height": 9},
    "tasks": "random",
}


def make() -> PettingZooEnv:
    return PettingZooEnv(warehouse_v1.env(**SMALL))


def test_collector_with_masked_random_policies() -> None:
    env = make()
    assert env.agents == ["robot_0", "robot_1", "robot_2"]
    algorithm = MultiAgentOffPolicyAlgorithm(
        algorithms=[
            MARLRandomDiscreteMaskedOffPolicyAlgorithm(env.action_space) for _ in env.agents
        ],
        env=env,
    )
    # One env and a plain buffer: a VectorReplayBuffer compiles numba code for 6 s.
    envs = DummyVectorEnv([make])
    envs.seed(0)
    buffer = ReplayBuffer(2000)
    # An illegal slot would raise InvalidActionError: every action honoured the mask.
    stats = Collector(algorithm, envs, buffer).collect(n_step=1000, reset_before_collect=True)
    assert stats.n_collected_steps == 1000
    assert stats.n_collected_episodes >= 20  # 40 decisions an episode
    # Per-robot returns (Tianshou reads the env's per-step rewards of every agent) add
    # up to minus the episode's travel delay, reported in the final step's info.
    returns = np.sort(stats.returns.sum(axis=1))
    done = np.flatnonzero(buffer.done[: len(buffer)])
    finals = np.sort(-buffer.info.ttd[done])
    np.testing.assert_allclose(returns, finals, rtol=1e-6)
    assert (buffer.info.decisions[done] == SMALL["num_tasks"]).all()
