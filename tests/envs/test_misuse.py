"""Misuse of the env APIs: each case is one of the project's errors with what to do.

PettingZoo (raw and wrapped), Gymnasium and the batched TorchRL env: calls before the
first ``reset()``, after ``close()``, unknown agents and ``reset`` options/keywords.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from typing import Any

import numpy as np
import pytest
import torch

from rtaw_marl import warehouse_v1
from rtaw_marl.envs.gymnasium import WarehouseEnv
from rtaw_marl.envs.torchrl import BatchedWarehouseEnv
from rtaw_marl.errors import (
    EnvUsageError,
    LayoutError,
    ResetNeededError,
    RtawError,
    UnknownAgentError,
)
from rtaw_marl.sim.builder import SimSpec

pytestmark = pytest.mark.unit

SMALL: dict[str, Any] = {
    "num_robots": 2,
    "queue_len": 3,
    "num_tasks": 6,
    "layout": {"name": "open", "width": 8, "height": 6},
    "tasks": "random",
}
FACTORIES = {"raw_env": warehouse_v1.raw_env, "env": warehouse_v1.env}
EACH_AEC = pytest.mark.parametrize("make", FACTORIES.values(), ids=FACTORIES.keys())
CLOSED = "after close(): this env is closed; make a new one"
NOT_RESET = "before reset(): call env.reset() first"


def _raises(error: type[Exception], message: str, call: Callable[[], object]) -> Exception:
    """``call()`` raises exactly ``error`` (not a subclass) with exactly ``message``."""
    with pytest.raises(error) as info:
        call()
    assert type(info.value) is error
    assert str(info.value) == message
    return info.value


# --------------------------------------------------------------------------- PettingZoo
@EACH_AEC
@pytest.mark.parametrize(
    ("name", "call"),
    [
        ("env.observe()", lambda env: env.observe("robot_0")),
        ("env.step()", lambda env: env.step(0)),
        ("env.last()", lambda env: env.last()),
        ("env.state()", lambda env: env.state()),
        ("env.observe_all()", lambda env: env.unwrapped.observe_all()),
    ],
)
def test_aec_calls_before_reset(make: Callable[..., Any], name: str, call: Callable) -> None:
    """Each call before the first reset is one ResetNeededError saying to reset first
    (PettingZoo's wrapper raises a bare AssertionError, the raw env an AttributeError)."""
    env = make(**SMALL)
    _raises(ResetNeededError, f"{name} {NOT_RESET}", lambda: call(env))
    env.reset(seed=0)
    call(env)


@EACH_AEC
@pytest.mark.parametrize(
    "name",
    ["agents", "agent_selection", "rewards", "terminations", "truncations", "infos", "num_agents"],
)
def test_aec_attributes_before_reset(make: Callable[..., Any], name: str) -> None:
    """Attributes set by reset are a ResetNeededError before it, also an AttributeError
    (PettingZoo's convention), so hasattr still answers False."""
    env = make(**SMALL)
    error = _raises(ResetNeededError, f"env.{name} {NOT_RESET}", lambda: getattr(env, name))
    assert isinstance(error, AttributeError)
    assert isinstance(error, RtawError)
    assert not hasattr(env, name)
    with pytest.raises(AttributeError, match="no attribute 'agent_selectoin'"):
        _ = env.agent_selectoin
    env.reset(seed=0)
    assert env.num_agents == 2


def test_wrapped_agent_iter_and_rendering_before_reset() -> None:
    """The wrapper's agent_iter and render before reset; the raw env renders nothing
    without a render mode, and refuses with one."""
    wrapped = warehouse_v1.env(render_mode="ansi", **SMALL)
    _raises(ResetNeededError, f"env.agent_iter() {NOT_RESET}", wrapped.agent_iter)
    _raises(ResetNeededError, f"env.render() {NOT_RESET}", wrapped.render)
    raw = warehouse_v1.raw_env(render_mode="ansi", **SMALL)
    _raises(ResetNeededError, f"env.render() {NOT_RESET}", raw.render)
    assert warehouse_v1.raw_env(**SMALL).render() is None
    raw.reset(seed=0)
    assert [len(row) for row in raw.render().split("\n")[:6]] == [8] * 6


@EACH_AEC
def test_unknown_agent_names(make: Callable[..., Any]) -> None:
    """An agent outside possible_agents is an UnknownAgentError (also a KeyError) whose
    message, not its repr, is the text; the env keeps working."""
    env = make(**SMALL)
    env.reset(seed=0)
    listed = "the agents are 'robot_0', 'robot_1'"
    for call in (env.observe, env.observation_space, env.action_space):
        error = _raises(
            UnknownAgentError,
            f"unknown agent 'nonexistent'; {listed}",
            lambda c=call: c("nonexistent"),
        )
        assert isinstance(error, KeyError)
    _raises(
        UnknownAgentError, f"unknown agent ['robot_0']; {listed}", lambda: env.observe(["robot_0"])
    )
    _raises(UnknownAgentError, f"unknown agent 0; {listed}", lambda: env.observe(0))
    env.step(int(np.flatnonzero(env.observe(env.agent_selection)["action_mask"])[0]))
    assert env.unwrapped.sim.decisions == 1


def test_unknown_agent_message_abbreviates_many_agents() -> None:
    env = warehouse_v1.raw_env(**{**SMALL, "num_robots": 12})
    env.reset(seed=0)
    _raises(
        UnknownAgentError,
        "unknown agent 'robot_12'; the agents are 'robot_0', 'robot_1', ..., 'robot_11'",
        lambda: env.observe("robot_12"),
    )


@EACH_AEC
def test_aec_calls_after_close(make: Callable[..., Any]) -> None:
    """After close() every call is an EnvUsageError (not a ResetNeededError), reset too;
    close() twice is fine."""
    env = make(**SMALL)
    env.reset(seed=0)
    env.close()
    env.close()
    for name, call in (
        ("env.step()", lambda: env.step(0)),
        ("env.observe()", lambda: env.observe("robot_0")),
        ("env.last()", env.last),
        ("env.state()", env.state),
        ("env.reset()", lambda: env.reset(seed=0)),
    ):
        _raises(EnvUsageError, f"{name} {CLOSED}", call)
    assert env.unwrapped.sim.decisions == 0


@EACH_AEC
@pytest.mark.parametrize(("options", "shown"), [("x", "str 'x'"), ([1], "list [1]"), (3, "int 3")])
def test_aec_reset_options_must_be_a_dict(
    make: Callable[..., Any], options: object, shown: str
) -> None:
    env = make(**SMALL)
    message = f"reset(options=...) takes a dict or None, got {shown}"
    _raises(EnvUsageError, message, lambda: env.reset(seed=0, options=options))
    _raises(ResetNeededError, f"env.step() {NOT_RESET}", lambda: env.step(0))


@EACH_AEC
def test_aec_reset_option_keys_are_warned_as_ignored(make: Callable[..., Any]) -> None:
    """The env has no reset options: a dict's keys are named in a warning (not an error,
    as PettingZoo's api_test passes a dummy key); None and {} are silent."""
    env = make(**SMALL)
    with pytest.warns(UserWarning, match="reset options") as caught:
        env.reset(seed=0, options={"seed": 3, "mode": "x"})
    assert [str(w.message) for w in caught] == [
        "reset options ['mode', 'seed'] ignored: warehouse_v1's reset takes no options"
    ]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        env.reset(seed=0, options={})
        env.reset(seed=0, options=None)
    assert env.unwrapped.np_random_seed == 0


@EACH_AEC
def test_failed_reset_leaves_the_env_unusable(make: Callable[..., Any], tmp_path: Any) -> None:
    """A reset that raises (a robot start on an obstacle, bad options mid-episode) leaves
    no half-built or abandoned episode to step: step is a ResetNeededError."""
    grid = tmp_path / "tiny.txt"
    grid.write_text("..@\n...\n")
    env = make(layout=str(grid), num_robots=1, robot_starts=[[2, 0]], tasks="random")
    with pytest.raises(LayoutError, match="obstacle"):
        env.reset(seed=0)
    _raises(ResetNeededError, f"env.step() {NOT_RESET}", lambda: env.step(0))
    env = make(**SMALL)
    env.reset(seed=0)
    with pytest.raises(EnvUsageError, match="takes a dict or None"):
        env.reset(seed=1, options="x")
    _raises(ResetNeededError, f"env.step() {NOT_RESET}", lambda: env.step(0))


# --------------------------------------------------------------------------- Gymnasium
def test_gymnasium_calls_before_reset_and_after_close() -> None:
    env = WarehouseEnv(render_mode="ansi", **SMALL)
    _raises(ResetNeededError, f"env.step() {NOT_RESET}", lambda: env.step(0))
    _raises(ResetNeededError, f"env.action_masks() {NOT_RESET}", env.action_masks)
    _raises(ResetNeededError, f"env.render() {NOT_RESET}", env.render)
    env.reset(seed=0)
    assert env.action_masks().tolist() == [True, True, True]
    env.step(0)
    env.close()
    env.close()
    _raises(EnvUsageError, f"env.step() {CLOSED}", lambda: env.step(0))
    _raises(EnvUsageError, f"env.reset() {CLOSED}", lambda: env.reset(seed=0))
    _raises(EnvUsageError, f"env.action_masks() {CLOSED}", env.action_masks)
    assert env.sim.decisions == 1


@pytest.mark.parametrize(
    ("options", "message"),
    [
        ("x", "reset(options=...) takes a dict or None, got str 'x'"),
        (
            {"seed": 3},
            "reset options ['seed'] are not known: rtaw/warehouse-single-v1's reset takes "
            "no options",
        ),
    ],
)
def test_gymnasium_reset_options(options: object, message: str) -> None:
    """The Gymnasium adapter refuses any option (its checkers pass only {})."""
    env = WarehouseEnv(**SMALL)
    _raises(EnvUsageError, message, lambda: env.reset(seed=0, options=options))
    obs, _ = env.reset(seed=0, options={})
    assert obs.shape == env.observation_space.shape


# --------------------------------------------------------------------------- TorchRL
def _batched(num_envs: int = 2) -> BatchedWarehouseEnv:
    spec = SimSpec.of(
        {k: SMALL[k] for k in ("num_robots", "queue_len", "num_tasks")},
        SMALL["layout"],
        "astar",
        "random",
    )
    return BatchedWarehouseEnv(spec, num_envs=num_envs)


def test_torchrl_calls_before_reset_and_after_close() -> None:
    env = _batched()
    td = env.full_action_spec.zero()
    _raises(ResetNeededError, f"env.step() {NOT_RESET}", lambda: env.step(td.clone()))
    _raises(ResetNeededError, f"env.episode_metrics() {NOT_RESET}", lambda: env.episode_metrics(0))
    td = env.reset()
    td["action"] = torch.zeros(2, dtype=torch.int64)
    env.step(td)
    assert [sim.decisions for sim in env.sims] == [1, 1]
    env.close()
    _raises(EnvUsageError, f"env.step() {CLOSED}", lambda: env.step(td))
    _raises(EnvUsageError, f"env.reset() {CLOSED}", env.reset)
    _raises(EnvUsageError, f"env.reset() {CLOSED}", lambda: env.reset_to([1, 2]))
    assert [sim.decisions for sim in env.sims] == [1, 1]


def test_torchrl_reset_keywords_and_metrics_index() -> None:
    """TorchRL hands reset's keywords to _reset: none is known, so each is refused (a
    seed there was silently ignored); a metrics index outside 0..B-1 is refused."""
    env = _batched()
    _raises(
        EnvUsageError,
        "reset() got unknown keyword arguments ['seed']; seed the env with set_seed(seed) "
        "or reset_to(seeds)",
        lambda: env.reset(seed=3),
    )
    env.reset()
    assert env.episode_metrics(1)["decisions"] == 0
    for index in (2, -1, True, 0.0):
        message = f"episode_metrics: no simulator {index!r}; the env has 2 (0..1)"
        _raises(EnvUsageError, message, lambda i=index: env.episode_metrics(i))
