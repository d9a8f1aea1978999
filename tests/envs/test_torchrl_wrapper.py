"""``warehouse_v1`` through TorchRL's ``PettingZooWrapper`` (the interop route).

The stock wrapper (``use_mask=True``, all robots in one group) and its vectorised
subclass :class:`WarehouseWrapper`, which ``rtaw_marl/training/interop.py`` builds:
specs pass ``check_env_specs`` from one robot to a thousand, the subclass's output is
bit-identical to the stock wrapper's over whole rollouts, observations land under the
keys the trainer reads, the episode metrics pass through as infos, and the benchmark
script runs.
"""

from __future__ import annotations

import warnings
from pathlib import Path
from typing import Any

import pytest
import torch
from torchrl.envs import PettingZooWrapper
from torchrl.envs.libs.pettingzoo import MarlGroupMapType
from torchrl.envs.utils import check_env_specs

from rtaw_marl import warehouse_v1
from rtaw_marl.envs.pettingzoo import zero_info
from rtaw_marl.envs.torchrl_wrapper import WarehouseWrapper
from rtaw_marl.sim.builder import SimSpec
from rtaw_marl.training.interop import INTEROP_KEYS, make_interop_env

pytestmark = pytest.mark.unit

REPO_ROOT = Path(__file__).resolve().parents[2]
OPEN = {"name": "open", "width": 40, "height": 40}


def aec(num_robots: int, observation: str, obs_format: str, **kwargs: Any) -> Any:
    return warehouse_v1.env(
        num_robots=num_robots, queue_len=4, layout=OPEN, navigator="direct", tasks="random",
        observation=observation, obs_format=obs_format, **{"num_tasks": 12, **kwargs},
    )  # fmt: skip


def wrapped(
    num_robots: int, observation: str, obs_format: str, return_state: bool = False, **kwargs: Any
) -> Any:
    """The stock wrapper."""
    env = aec(num_robots, observation, obs_format, **kwargs)
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=r"PettingZoo in TorchRL is tested using")
        return PettingZooWrapper(
            env, use_mask=True, group_map=MarlGroupMapType.ALL_IN_ONE_GROUP, seed=0,
            return_state=return_state,
        )  # fmt: skip


@pytest.mark.parametrize(
    ("num_robots", "observation", "obs_format"),
    [
        (1, "full", "dict"),
        (1, "compact", "flat"),
        (10, "full", "dict"),
        (10, "full", "flat"),
        (10, "compact", "dict"),
        (10, "compact", "flat"),
        (1000, "compact", "flat"),
    ],
)
@pytest.mark.parametrize("vectorised", [False, True], ids=["stock", "vectorised"])
def test_check_env_specs(
    num_robots: int, observation: str, obs_format: str, vectorised: bool
) -> None:
    if vectorised:
        env = WarehouseWrapper(aec(num_robots, observation, obs_format), seed=0)
    else:
        env = wrapped(num_robots, observation, obs_format)
    check_env_specs(env, seed=0)
    td = env.reset()
    features = td["agents", "observation", "observation"]
    if obs_format == "flat":
        assert features.shape == (num_robots, env.unwrapped.obs_layout.flat_size)
    else:
        expected = {"tasks", "agent", "relations", "rivals"} | (
            {"robots"} if observation == "full" else set()
        )
        assert set(features.keys()) == expected
    assert td["agents", "mask"].sum() == 1  # one robot acts


@pytest.mark.parametrize(
    ("num_robots", "observation", "obs_format", "return_state"),
    [
        (1, "full", "dict", False),
        (4, "full", "dict", True),
        (4, "full", "flat", False),
        (4, "compact", "dict", False),
        (6, "compact", "flat", True),
    ],
)
def test_vectorised_wrapper_equals_the_stock_wrapper(
    num_robots: int, observation: str, obs_format: str, return_state: bool
) -> None:
    """Whole rollouts over several episodes (random masked actions, auto-reset): every
    entry of every step is bit-identical, including masks, rewards, flags and infos."""
    kwargs = {"num_tasks": 9, "episode_mode": "paper" if return_state else "drain"}
    stock = wrapped(num_robots, observation, obs_format, return_state=return_state, **kwargs)
    fast = WarehouseWrapper(
        aec(num_robots, observation, obs_format, **kwargs), seed=0, return_state=return_state
    )
    rollouts = []
    for env in (stock, fast):
        torch.manual_seed(7)
        rollouts.append(env.rollout(40, break_when_any_done=False))
    expected, got = rollouts
    assert expected["next", "done"].sum() >= 3  # episodes ended and restarted
    assert set(got.keys(True, True)) == set(expected.keys(True, True))
    for key in expected.keys(True, True):
        assert got[key].dtype == expected[key].dtype, key
        assert torch.equal(got[key], expected[key]), key


def test_vectorised_wrapper_refuses_other_envs() -> None:
    from pettingzoo.test.example_envs import generated_agents_env_v0

    with pytest.raises(TypeError, match="wraps the warehouse_v1 env"):
        WarehouseWrapper(generated_agents_env_v0.env())


def test_infos_pass_through_and_hold_the_final_metrics() -> None:
    env = wrapped(2, "compact", "flat", num_tasks=3)
    td = env.reset()
    info = td["agents", "info"]
    assert set(info.keys()) == set(zero_info())
    assert all((info[key] == 0).all() for key in info.keys())  # noqa: SIM118 (rows otherwise)
    aec = env.unwrapped  # the wrapper forwards to the AEC env: its raw env
    for _ in range(3):
        td["agents", "action"] = td["agents", "action_mask"].to(torch.uint8).argmax(-1)
        out = env.step(td)
        td = out["next"]
    assert td["done"].item()
    final = aec.sim.metrics().as_dict()
    for key, value in final.items():
        assert td["agents", "info", key] == pytest.approx(torch.full((2,), float(value)))
    assert final["decisions"] == 3


@pytest.mark.parametrize("model", ["rtaw", "rtaw_plus"])
def test_interop_keys_name_entries_of_the_wrapped_env(model: str) -> None:
    """Every input of both models' networks is a key of the interop env's tensordict."""
    from rtaw_marl.models.checkpoint import build_networks
    from rtaw_marl.models.config import RTAWConfig, RTAWPlusConfig

    cfg = RTAWConfig() if model == "rtaw" else RTAWPlusConfig()
    actor, critic = build_networks(cfg)
    spec = SimSpec.of({"num_robots": 3, "num_tasks": 6, "queue_len": 4}, OPEN, "direct", "random")
    td = make_interop_env(spec, seed=0).reset()
    for net in (actor, critic):
        for key in INTEROP_KEYS.observation(net.in_keys):
            assert key in td.keys(True, True), key
    assert INTEROP_KEYS.loss_mask in td.keys(True, True)
