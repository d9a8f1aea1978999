"""The rules' one input: built from the simulator or from the observation, it holds the
same decision (the rules' two paths differ only in these builders)."""

from __future__ import annotations

import numpy as np
import pytest

from rtaw_marl import warehouse_v1
from rtaw_marl.decision.rule_input import RULE_NEEDS, RuleInput, free_times
from rtaw_marl.errors import ConfigError

pytestmark = pytest.mark.unit


@pytest.mark.parametrize("navigator", ["direct", "astar", "sipp"])
def test_both_builders_hold_the_same_decision(navigator: str) -> None:
    """At every decision of an episode (noise on: times are not whole seconds), the
    builders agree exactly on cells, times, the acting row and the navigator's distances,
    and on the acting robot's distances to the observation's float32 precision."""
    env = warehouse_v1.env(num_robots=6, num_tasks=30, layout="A", navigator=navigator)
    env.reset(seed=3)
    sim = env.unwrapped.sim
    checked = 0
    for _ in env.agent_iter():
        obs, _, terminated, truncated, _ = env.last()
        if terminated or truncated:
            env.step(None)
            continue
        fast = RuleInput.of_sim(sim, RULE_NEEDS)
        read = RuleInput.of_observation(
            obs, RULE_NEEDS, distance_model=sim.distance_model, scale=sim.layout.scale,
            noise_mean=sim.config.noise_mean, reader="test",
        )  # fmt: skip
        mask = fast.mask
        np.testing.assert_array_equal(read.mask, mask)
        assert read.robot == fast.robot
        assert np.all(read.robot_xy[fast.robot] == sim.robot_xy[sim.robot])
        for field in ("robot_xy", "free_in", "queue_rows"):
            np.testing.assert_array_equal(getattr(read, field), getattr(fast, field), field)
        np.testing.assert_array_equal(read.distances[:, mask], fast.distances[:, mask])
        np.testing.assert_allclose(
            read.own_distances[mask], fast.own_distances[mask], rtol=1e-6, atol=1e-6
        )
        assert (read.noise_mean, read.scale) == (fast.noise_mean, fast.scale)
        checked += 1
        env.step(int(np.flatnonzero(mask)[0]))
    assert checked == 30


def test_only_the_needs_are_built() -> None:
    env = warehouse_v1.env(num_robots=3, num_tasks=5)
    env.reset(seed=0)
    sim = env.unwrapped.sim
    bare = RuleInput.of_sim(sim)
    assert bare.own_distances is bare.distances is bare.robot is bare.queue_rows is None
    # No feature is read when none is needed: a mask alone is a valid observation.
    mask = np.array([0, 1, 1], dtype=np.int8)
    read = RuleInput.of_observation({"action_mask": mask})
    np.testing.assert_array_equal(read.mask, [False, True, True])
    with pytest.raises(ValueError, match="unknown needs"):
        RuleInput.of_sim(sim, ("tasks",))


def test_the_observation_path_names_what_it_lacks() -> None:
    env = warehouse_v1.env(num_robots=3, num_tasks=5, observation="compact")
    env.reset(seed=0)
    obs = env.observe(env.agent_selection)
    with pytest.raises(ConfigError, match=r"r1 on observations needs the env's distance model "
                       r"and noise mean: make_baseline\('r1', env=env\)"):  # fmt: skip
        RuleInput.of_observation(obs, ("distances", "noise_mean"), reader="r1")
    nav = env.unwrapped.sim.distance_model
    with pytest.raises(ConfigError, match=r"r2 reads robots.*observation=.full."):
        RuleInput.of_observation(obs, ("robot",), distance_model=nav, reader="r2")


def test_free_times_restore_whole_milliseconds() -> None:
    """Times to the millisecond come back exactly from float32 (ties stay ties); others
    keep the observation's value."""
    scale = 60.0
    times = np.array([0.0, 3.0, 3.0, 12.345, 7.123456789])
    column = (times / scale).astype(np.float32)
    back = free_times(column, scale)
    np.testing.assert_array_equal(back[:4], times[:4])
    assert back[4] == pytest.approx(times[4], rel=1e-6)


def test_own_row_is_the_robot_itself_on_the_fast_path() -> None:
    """``own_row`` gives the acting robot's own index without a search on the fast path,
    and a row equal to it on the observation path (the first equal row: robots on one
    cell, freed at once); either way their rows, all RBTS reads, are equal."""
    # Four robots start idle on one cell: at t = 0 their rows are equal.
    env = warehouse_v1.env(num_robots=4, num_tasks=20, layout="A", robot_starts=[[3, 3]] * 4)
    env.reset(seed=1)
    sim = env.unwrapped.sim
    for _ in env.agent_iter():
        obs, _, terminated, truncated, _ = env.last()
        if terminated or truncated:
            env.step(None)
            continue
        fast = RuleInput.of_sim(sim, {"own_row", "robot_xy", "free_in"})
        read = RuleInput.of_observation(
            obs, {"own_row", "robot_xy", "free_in"}, scale=sim.layout.scale, reader="test"
        )
        assert fast.robot == sim.robot
        assert np.array_equal(read.robot_xy[read.robot], fast.robot_xy[fast.robot])
        assert read.free_in[read.robot] == fast.free_in[fast.robot]
        env.step(int(np.flatnonzero(obs["action_mask"])[0]))
