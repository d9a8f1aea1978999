"""# RTAW Warehouse, single-agent Gymnasium adapter (`rtaw/warehouse-single-v1`)

The warehouse of `warehouse_v1` ([environment.md](environment.md)) as a Gymnasium
`Env`: one decision per `step`, taken for whichever robot is free, so one policy serves
every robot (the single decision stream that `rtaw-train`'s batched env also gives its
shared policy). For single-agent libraries: Stable-Baselines3 and SB3-contrib's
`MaskablePPO`, SuperSuit's Gymnasium wrappers, any `gymnasium.Env` consumer; versions
tested and snippets: [integrations.md](integrations.md).

| Import             | `from rtaw_marl.envs.gymnasium import WarehouseEnv`                     |
|--------------------|-------------------------------------------------------------------------|
| Make               | `gymnasium.make("rtaw/warehouse-single-v1", num_robots=10, ...)`        |
| Actions            | `Discrete(queue_len)`                                                   |
| Observation        | `Box(-inf, inf, (3M + 46N + 3,), float32)` (flat, default)              |
| Action mask        | `env.action_masks()` (bool) and `info["action_mask"]` (int8)            |
| Reward             | the reward of the decision taken in this `step`                         |
| Episode            | `num_tasks` steps                                                       |

## Registration

Importing this module registers `rtaw/warehouse-single-v1` with `gymnasium.register`; so do
`from rtaw_marl import warehouse_v1`, `rtaw_marl.register_envs()`, and importing
`rtaw_marl` after `gymnasium`. From a fresh interpreter,
`gymnasium.make("rtaw_marl.envs.gymnasium:rtaw/warehouse-single-v1")` imports and registers in
one call. `gymnasium.make` adds Gymnasium's usual `PassiveEnvChecker` and
`OrderEnforcing` wrappers and no `TimeLimit`.

## Observation

The acting robot's features, exactly the `"observation"` entry of the PettingZoo env's
`observe(agent)` for the selected agent (same options, same values; every feature is in
[environment.md](environment.md#observation)): with `obs_format="flat"` (default) a
float32 vector of `3M + 46N + 3` values (`observation="full"`, default) or `46N + 3`
(`observation="compact"`); with `obs_format="dict"` a `Dict` of the feature arrays. The
spaces are `Box(-inf, inf)`, as in the PettingZoo env; `env.unwrapped.obs_layout` has
`flat_slices` and `unflatten`. Every `reset` and `step` returns new arrays. The robot
an observation belongs to is `env.unwrapped.sim.robot`.

## Action mask

`info["action_mask"]` (int8 `[N]`, Gymnasium's `Discrete.sample(mask=...)`
convention) and `action_masks()` (bool `[N]`, SB3-contrib's `MaskablePPO`
convention): 1 for the slots holding a task. After the last decision it is all zeros.

## Actions

A queue slot (a Python or NumPy integer): the acting robot takes that task. An empty or
out-of-range slot, or anything that is not an integer, raises
`rtaw_marl.errors.InvalidActionError` and leaves the env as it was.

## Rewards

The reward of the decision just taken: minus its travel delay (`reward="ttd"`; or the
ablations `"length"`, `"ttd_length"`, `"pair_cost"`). It is what the simulator returns for the
decision, not the PettingZoo `step(); last()` pattern, which would hand back the *next*
robot's reward from its previous decision (the credit of another decision). Over an
episode the rewards add up to minus `info["ttd"]`.

## Termination and truncation

An episode is `num_tasks` steps. `episode_mode="drain"` (default): the last step is
`terminated`; `"paper"` (the queue is always refilled): it is `truncated`.

## Infos

`info` holds `action_mask` and the episode metrics as flat keys (`ttd`,
`makespan`, `task_length`, `idle_mean`, `idle_max`, `wait_mean`, `wait_max`,
`tasks_served`, `decisions`): zeros until the last step, the episode's metrics in the
last step's `info` (the same keys at every step, for vectorised envs).

## Seeding

`reset(seed=s)` (`s` an integer `>= 0`, else `ConfigError`) reseeds `np_random`
(Gymnasium's `Env.reset`) and fixes the episode: the same episode as the PettingZoo
env's `reset(seed=s)`. `reset()` without a seed draws the episode seed from
`np_random`, so a seeded sequence of episodes is reproducible.

## Misuse

`step`, `render` and `action_masks` before the first `reset()` raise
`rtaw_marl.errors.ResetNeededError` (through `gymnasium.make`, Gymnasium's
`OrderEnforcing` raises its `ResetNeeded` first); any call after `close()` raises
`EnvUsageError`; `reset(options=...)` takes `None` or a dict with no keys (the env has no
reset options), anything else raises `EnvUsageError` naming what was passed.

## Rendering

`render_mode="ansi"`: `render()` returns the grid as text (legend in
[environment.md](environment.md#rendering)); `"human"`: the text is printed at every
`reset` and `step`.

## Arguments

`WarehouseEnv(layout=None, navigator=None, tasks=None, render_mode=None,
observation="full", obs_format="flat", scenario=None, **sim_keys)`: as the PettingZoo
env's `env(...)` (`**sim_keys` the `SimConfig` keys, the `sim.*` config keys:
`num_robots`, `num_tasks`, `queue_len`, `episode_mode`, `noise_mean`, `noise_var`,
`reward`, ...; `scenario` a named setting, which the groups and keys given override),
only `obs_format` defaults to `"flat"`; an unknown key, option or scenario is a
`ConfigError` listing them.

## Version History

* v1: initial release (the features of `warehouse_v1`).
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping
from typing import Any, ClassVar

import gymnasium
import numpy as np
from gymnasium import spaces

from rtaw_marl import register_envs
from rtaw_marl.decision.observations import AgentViews, ObservationLayout
from rtaw_marl.envs.pettingzoo import reset_option_keys, zero_info
from rtaw_marl.envs.spaces import features_space
from rtaw_marl.envs.text import render_ansi
from rtaw_marl.errors import ConfigError, EnvUsageError, usage_error
from rtaw_marl.scenarios import Scenario
from rtaw_marl.scenarios.merge import spec_with
from rtaw_marl.sim.builder import build_sim
from rtaw_marl.sim.core import WarehouseSim
from rtaw_marl.sim.inputs import draw_training_seed, seed_value
from rtaw_marl.sim.options import LayoutOption, NavigatorOption, TaskOption

__all__ = ["WarehouseEnv", "deprecated_env"]

Features = np.ndarray | dict[str, np.ndarray]
Info = dict[str, Any]


class WarehouseEnv(gymnasium.Env):
    """The warehouse as a single-agent Gymnasium env; see the module docstring."""

    metadata: ClassVar[dict[str, Any]] = {"render_modes": ["human", "ansi"]}

    def __init__(
        self,
        layout: str | Mapping[str, Any] | LayoutOption | None = None,
        navigator: str | Mapping[str, Any] | NavigatorOption | None = None,
        tasks: str | Mapping[str, Any] | TaskOption | None = None,
        render_mode: str | None = None,
        *,
        observation: str = "full",
        obs_format: str = "flat",
        scenario: str | Scenario | None = None,
        **sim_keys: Any,
    ) -> None:
        """Build the env (module docstring, *Arguments*).

        Raises:
            ConfigError: An unknown or invalid option or key.
        """
        # Live from reset() to close(); one flag read is all the hot path pays.
        self._live, self._closed = False, False
        modes = self.metadata["render_modes"]
        if render_mode is not None and render_mode not in modes:
            raise ConfigError(
                f"Unknown render_mode {render_mode!r}. Available: None, {', '.join(modes)}"
            )
        spec = spec_with(scenario, sim_keys, layout, navigator, tasks)
        self.obs_layout = ObservationLayout(
            observation, obs_format, spec.sim.num_robots, spec.sim.queue_len
        )
        self.sim: WarehouseSim = build_sim(spec)
        self.render_mode = render_mode
        self.observation_space = features_space(self.obs_layout)
        self.action_space = spaces.Discrete(spec.sim.queue_len)
        self._views = AgentViews(self.sim, self.obs_layout)
        self._robot = 0  # the robot of the last observation handed out
        self._mask = np.zeros(spec.sim.queue_len, dtype=np.int8)

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[Features, Info]:
        """Start an episode; ``seed`` reseeds ``np_random`` and fixes the episode.

        Raises:
            ConfigError: ``seed`` is neither ``None`` nor an integer ``>= 0``.
            EnvUsageError: ``options`` is not ``None`` or an empty dict (the env takes no
                reset options), or the env is closed.
        """
        if self._closed:
            raise usage_error("env.reset()", closed=True)
        # Not live until the new episode is built: a reset that raises leaves none to step.
        self._live = False
        if keys := reset_option_keys(options):
            raise EnvUsageError(
                f"reset options {keys} are not known: rtaw/warehouse-single-v1's reset "
                "takes no options"
            )
        if seed is not None:
            seed = seed_value(seed)
        super().reset(seed=seed)
        self.sim.reset(seed if seed is not None else draw_training_seed(self.np_random))
        self._live = True
        self._views.clear()
        obs, info = self._observe(self.sim.robot, zero_info())
        if self.render_mode == "human":
            self.render()
        return obs, info

    def step(self, action: int) -> tuple[Features, float, bool, bool, Info]:
        """The acting robot takes queue slot ``action``; returns that decision's reward.

        Raises:
            InvalidActionError: ``action`` is not a queue slot holding a task, or the
                episode is over; the env is unchanged.
            EnvUsageError: Before ``reset()`` (:class:`ResetNeededError`) or after ``close()``.
        """
        if not self._live:
            raise usage_error("env.step()", self._closed)
        sim = self.sim
        reward = sim.step(action)
        done = sim.done
        # After the last decision: the acting robot's own (final) view, with a zero mask.
        obs, info = self._observe(
            self._robot if done else sim.robot, sim.metrics().as_dict() if done else zero_info()
        )
        if self.render_mode == "human":
            self.render()
        return obs, reward, done and not sim.truncated, sim.truncated, info

    def _observe(self, robot: int, metrics: Info) -> tuple[Features, Info]:
        self._robot = robot
        view = self._views.observe(robot)
        self._mask = view["action_mask"]
        return view["observation"], {"action_mask": self._mask, **metrics}

    def action_masks(self) -> np.ndarray:
        """The legal slots of the current decision, ``bool [N]`` (``MaskablePPO``)."""
        if not self._live:
            raise usage_error("env.action_masks()", self._closed)
        return self._mask.astype(bool)

    def close(self) -> None:
        """End the env's use: every later call raises :class:`EnvUsageError`."""
        self._live, self._closed = False, True

    def render(self) -> str | None:
        """The grid as text (``"ansi"``), printed (``"human"``), or ``None`` (no mode)."""
        if self.render_mode is None:
            return None
        if not self._live:
            raise usage_error("env.render()", self._closed)
        text = render_ansi(self.sim)
        if self.render_mode == "human":
            print(text)
            return None
        return text


register_envs()


def deprecated_env(**kwargs: Any) -> WarehouseEnv:
    """The entry point of the adapter's old id ``rtaw/Warehouse-v1``: the same env, with a
    ``DeprecationWarning`` naming ``rtaw/warehouse-single-v1``."""
    warnings.warn(
        "rtaw/Warehouse-v1 is deprecated, use rtaw/warehouse-single-v1",
        DeprecationWarning,
        stacklevel=2,
    )
    return WarehouseEnv(**kwargs)
