"""The AEC env under LoRR's reassignment: the observation shows the reassignable tasks
(legal beyond the action mask, which stays the unassigned tasks); taking one frees its
holder, who acts next."""

from __future__ import annotations

import numpy as np
import pytest
from pettingzoo.test import api_test
from pettingzoo.utils.env import AECEnv

from rtaw_marl import warehouse_v1

pytestmark = pytest.mark.integration


def _env() -> AECEnv:
    from rtaw_marl.scenarios.lorr import lorr_scenario

    scenario = lorr_scenario("builtin:random_32_32_20_100.json", horizon=60)
    return warehouse_v1.env(scenario=scenario)


def test_observation_shows_reassignable_tasks_and_step_takes_them() -> None:
    env = _env()
    env.reset(seed=0)
    sim = env.unwrapped.sim
    taken = 0
    for agent in env.agent_iter():
        obs, _, term, trunc, _ = env.last()
        if term or trunc:
            env.step(None)
            continue
        assert env.observation_space(agent).contains(obs)
        held = obs["reassignable"].astype(bool)
        np.testing.assert_array_equal(held, sim.reassignable())
        np.testing.assert_array_equal(obs["action_mask"].astype(bool), sim.queue_mask)
        assert not (held & sim.queue_mask).any()
        other = env.observe(env.agents[(env.agents.index(agent) + 1) % len(env.agents)])
        assert not other["reassignable"].any()
        if held.any() and taken < 20:
            slot = int(np.flatnonzero(held)[0])
            holder = int(sim.queue_holder[slot])
            env.step(slot)
            taken += 1
            assert holder in sim.free_robots().tolist()
        else:
            env.step(int(np.flatnonzero(obs["action_mask"])[0]))
    assert taken == 20


def test_api_with_reassignment() -> None:
    api_test(_env(), num_cycles=30)
