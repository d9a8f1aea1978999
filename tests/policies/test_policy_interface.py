"""One policy interface: every policy plays the same episode through the PettingZoo env
(``act(obs)``) and on the bare simulator (``act_sim``), on every navigator, with the
default noise, and makes the same decisions."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from rtaw_marl import warehouse_v1
from rtaw_marl.errors import ConfigError
from rtaw_marl.evaluation import run_episode
from rtaw_marl.policies import BASELINES, BaselinesConfig, Policy, make_baseline
from rtaw_marl.sim.core import WarehouseSim

pytest.importorskip("torch")
from rtaw_marl.policies import load_policy

pytestmark = pytest.mark.integration

NAVIGATORS = ("direct", "astar", "sipp", "cbs")
RULES = ("mpdm", "rbts", "random", "lookahead", "hungarian")
NETWORKS = ("shelves_astar_m10", "shelves_astar_m10_plus")
SIZE: dict[str, Any] = {"num_robots": 10, "num_tasks": 30, "layout": "shelves"}
SEED = 5


def _make(name: str, env: Any) -> Policy:
    return load_policy(name) if name in NETWORKS else make_baseline(name, env=env)


def _play_env(name: str, navigator: str, **options: Any) -> tuple[list[int], float]:
    env = warehouse_v1.env(navigator=navigator, **SIZE, **options)
    return _play(env, _make(name, env))


def _play(env: Any, policy: Policy) -> tuple[list[int], float]:
    """One episode of ``policy`` acting on ``env``'s observations: its actions and TTD."""
    env.reset(seed=SEED)
    policy.reset(SEED)
    actions: list[int] = []
    for _ in env.agent_iter():
        obs, _, terminated, truncated, info = env.last()
        action = None if terminated or truncated else policy.act(obs)
        if action is not None:
            actions.append(action)
        env.step(action)
    return actions, info["ttd"]


def _play_sim(name: str, navigator: str) -> tuple[list[int], float]:
    sim: WarehouseSim = warehouse_v1.env(navigator=navigator, **SIZE).unwrapped.sim
    policy = _make(name, sim)
    actions: list[int] = []

    class Recorder:
        def reset(self, seed: int | None = None) -> None:
            policy.reset(seed)

        def act_sim(self, s: WarehouseSim) -> int:
            actions.append(policy.act_sim(s))
            return actions[-1]

    metrics = run_episode(sim, Recorder(), SEED)
    return actions, metrics.ttd


#: Every policy on every navigator (the hindsight reference has no observation path).
CASES = [(name, nav) for name in (*RULES, *NETWORKS) for nav in NAVIGATORS]


@pytest.mark.parametrize(("name", "navigator"), CASES)
def test_act_and_act_sim_make_the_same_decisions(name: str, navigator: str) -> None:
    expected, expected_ttd = _play_sim(name, navigator)
    actions, ttd = _play_env(name, navigator)
    assert len(actions) == SIZE["num_tasks"]
    assert actions == expected
    assert ttd == expected_ttd


@pytest.mark.parametrize(
    ("name", "options"),
    [
        ("shelves_astar_m10_plus", {"observation": "compact"}),
        ("shelves_astar_m10_plus", {"obs_format": "flat"}),
        ("shelves_astar_m10_plus", {"observation": "compact", "obs_format": "flat"}),
        ("shelves_astar_m10", {"obs_format": "flat"}),
        ("lookahead", {"obs_format": "flat"}),
    ],
)
def test_every_format_that_holds_the_features(name: str, options: dict[str, Any]) -> None:
    assert _play_env(name, "astar", **options) == _play_env(name, "astar")


def test_lookahead_on_k_candidates_agrees_both_ways() -> None:
    """``lookahead_candidates=K`` ranks the K nearest tasks on the observation path too
    (its own distance column), and so chooses what the fast path chooses."""
    size = {**SIZE, "queue_len": 12}
    params = BaselinesConfig(lookahead_candidates=4)
    env = warehouse_v1.env(navigator="astar", **size)
    actions, ttd = _play(env, make_baseline("lookahead", env=env, params=params))
    sim = warehouse_v1.env(navigator="astar", **size).unwrapped.sim
    fast = make_baseline("lookahead", params=params)
    fast.reset(SEED)
    sim.reset(SEED)
    expected = []
    while not sim.done:
        expected.append(fast.act_sim(sim))
        sim.step(expected[-1])
    assert actions == expected
    assert ttd == sim.metrics().ttd


def test_the_default_noise_is_modelled() -> None:
    """Through the env lookahead is the tables' policy: the simulator's noise mean."""
    env = warehouse_v1.env(**SIZE)
    policy = make_baseline("lookahead", env=env)
    assert policy.noise_mean == env.unwrapped.sim.config.noise_mean == 0.25


def test_missing_features_are_named() -> None:
    env = warehouse_v1.env(observation="compact", **SIZE)
    env.reset(seed=0)
    obs = env.observe(env.agent_selection)
    for name in ("shelves_astar_m10", "rbts", "hungarian"):
        with pytest.raises(ConfigError, match=r"reads robots.*observation=.full."):
            _make(name, env).act(obs)


def test_every_policy_is_a_policy_and_hindsight_says_why_it_cannot_act() -> None:
    env = warehouse_v1.env(**SIZE)
    env.reset(seed=0)
    for name in [*BASELINES, *NETWORKS]:
        assert isinstance(_make(name, env), Policy)
    with pytest.raises(NotImplementedError, match="future"):
        make_baseline("hindsight", env=env).act(env.observe(env.agent_selection))


def test_load_policy_names_and_threads() -> None:
    import torch

    before = torch.get_num_threads()
    try:
        torch.set_num_threads(2)
        load_policy("shelves_astar_m10_plus", torch_threads=None)
        assert torch.get_num_threads() == 2
        policy = load_policy("shelves_astar_m10_plus")
        assert torch.get_num_threads() == 1
        assert policy.name == "shelves_astar_m10_plus"
    finally:
        torch.set_num_threads(before)
    with pytest.raises(ConfigError, match="did you mean shelves_astar_m10_plus"):
        load_policy("shelves_astar_m10_pluss")


def _readme_snippet() -> str:
    """The README's Python block that acts with ``load_policy`` (run verbatim)."""
    text = (Path(__file__).resolve().parents[2] / "README.md").read_text()
    blocks = re.findall(r"```python\n(.*?)```", text, re.S)
    (snippet,) = [b for b in blocks if "load_policy" in b]
    return snippet


def test_readme_snippet(capsys: pytest.CaptureFixture[str]) -> None:
    """The README's snippet, verbatim: its TTD is the evaluation's (act_sim) for seed 0."""
    exec(compile(_readme_snippet(), "README.md", "exec"), {})
    printed = float(capsys.readouterr().out.strip())
    sim = warehouse_v1.env(num_robots=10, layout="shelves", navigator="astar").unwrapped.sim
    expected = run_episode(sim, load_policy("shelves_astar_m10_plus"), 0).ttd
    assert printed == expected
    assert np.isfinite(printed)
