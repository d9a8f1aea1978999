"""# RTAW Warehouse (``warehouse_v1``)

Lifelong multi-robot task allocation in a warehouse grid (the RTAW paper's MDP) as a
PettingZoo AEC environment. Whenever a robot becomes free it is the acting agent and
picks one task from a queue of ``N`` visible tasks; its cost is the empty travel to the
task's pickup (the *travel delay*).

| Import             | `from rtaw_marl import warehouse_v1`                        |
|--------------------|-------------------------------------------------------------|
| Actions            | Discrete                                                    |
| Parallel API       | No (one robot acts at a time)                               |
| Manual control     | No                                                          |
| Agents             | `agents = ['robot_0', ..., 'robot_{M-1}']`                  |
| Number of agents   | `num_robots` (M)                                            |
| Action shape       | `()`                                                        |
| Action values      | `Discrete(queue_len)`                                       |
| Observation shape  | `{"observation": features, "action_mask": (N,)}`            |
| Observation values | float32 features (dict or flat vector), int8 mask          |
| State shape        | `(3M + 7N,)`                                                |
| State values       | float32, `>= 0`                                             |

## Agents and turn order

`agent_selection` is always the robot that becomes free next (the one with the
smallest free time; ties go to the lowest robot id). It picks a task, travels to the
task's origin and on to its destination, and becomes free again at completion time plus
Gaussian noise (`noise_mean`, `noise_var`). Decisions happen at irregular times, so
the same robot may act several times in a row.

## Observation

`observe(agent)` returns PettingZoo's masked layout `{"observation": features,
"action_mask": mask}`. Two constructor options choose the features:

* `observation="full"` (default): `robots`, `tasks`, `agent`, `relations`, `rivals`;
  `observation="compact"`: the same without `robots`, so its size does not depend on
  `M` (`rivals` summarises the other robots; the robot table is in `state()`).
* `obs_format="dict"` (default): a dict of arrays; `obs_format="flat"`: one float32
  vector, a Box for Box-only wrappers (SuperSuit's, once the entry is taken out of the
  masked dict: docs/integrations.md): the arrays flattened in C order and concatenated
  in the order listed, `3M + 46N + 3` values (full) or `46N + 3` (compact).
  `env.unwrapped.obs_layout` has `flat_slices` and `unflatten(vector)`.

`env.unwrapped.observe_all()` returns every agent's observation at once, stacked in
`possible_agents` order: `{"observation": features [M, ...], "action_mask": [M, N]}`.
A learned policy decides for stacked observations with one network call:
`load_policy(name).act_batch(observations)` (`-1` for rows with an all-zero mask).

Features are float32. Lengths and times are divided by the layout scale `L = max(W, H)`
(robots move one cell per second); coordinates use `x` = column, `y` = row.

* `robots` `[M, 3]` (full only): for every robot, `(x / L, y / L, time_until_free / L)`,
  in `[0, 1] x [0, 1] x [0, inf)`. The cell is where the robot will be when next free
  (its current task's destination).
* `tasks` `[N, 6]`: for every queue slot, `(ox, oy, dx, dy, k, l) / L`, all `>= 0`:
  origin, destination, `k` the travel distance from *this* robot to the origin and `l`
  the task length (origin -> destination). Empty slots (possible at the end of a
  `drain` episode) are all zeros.
* `agent` `[3]`: this robot's own row of `robots`.
* `relations` `[N, 8]`: each slot from *this* robot's point of view, divided by `L`:
  its distance `k` to the origin, the task length, the time the task has waited, the
  arrival of the three fastest rivals minus `k`, a soft-min (temperature `0.05 L`) of
  the rivals' arrivals minus `k` (these four are negative when a rival arrives first),
  and the distance from the destination to the nearest other queued origin. A robot's
  *arrival* is its time until free plus its distance; *rivals* are the other robots. A
  missing rival or chain partner counts as `2` (two layout scales away).
* `rivals` `[N, 8, 4]`: per slot, the 8 rivals arriving first (sorted; ties: lowest
  robot id), each `(arrival - k, time_until_free, distance) / L` and a validity flag
  (0 for the padding rows when there are fewer than 9 robots).

The feature spaces are `Box(-inf, inf)` (the real ranges are above): TorchRL's
`PettingZooWrapper` copies the bounds of all `M` agents once per agent per step, so
finite bounds cost `O(M^2)` per step (a wrapper that needs finite bounds, such as
SuperSuit's `normalize_obs_v0`, takes squashed features: docs/integrations.md).
`observation_spaces` and `action_spaces` map every agent to one shared space object.
Arrays are shared until the next decision (`robots` between agents): copy one before
modifying it. The acting robot's features are bit-identical to the batched TorchRL env's.

## Action mask

`action_mask` `[N]` int8: 1 for the slots holding a task. The mask of any agent other
than the selected one is all zeros (TorchRL's `PettingZooWrapper` gives those rows an
all-True mask and marks the acting row in `("agents", "mask")`).

With LoRR's reassignment (`sim.reassign=true`, the default of `scenario=lorr`) a task
stays in its slot, *held*, until its robot reaches the pickup; the observation gains
`reassignable` `[N]` int8 (1 for the held slots the acting robot may take: not moved
yet in this timestep; zeros for other agents). They are legal actions beyond
`action_mask`, which stays the unassigned tasks, so a policy or library that knows
nothing of reassignment acts as before. Taking one frees its holder where it stands;
the holder acts next, in the same timestep.

## State

`state()` is the global state, `float32 [3M + 7N]` in `state_space = Box(0, inf)`: the
robot table `[M, 3]` (the `robots` feature), then the queue `[N, 7]`: `(ox, oy, dx, dy,
length, wait) / L` and `queued` (1 or 0) per slot (empty slots are zeros), flattened in
C order. The acting robot is the first one whose time until free is 0.

## Actions

A queue slot: a Python or NumPy integer (or a 0-d integer array); the slot is refilled
from the task stream. Anything else raises `rtaw_marl.errors.InvalidActionError` and
leaves the env as it was: an out-of-range or empty slot, a float (even `1.0`), a bool,
a string, an array of shape other than `()`, or `None` for a live agent. `None` is the
only valid action of a terminated or truncated agent.

## Rewards

Minus the travel delay of the chosen task (`reward="ttd"`, the paper's reward), or for
the paper's ablation minus the task length (`"length"`) or their sum
(`"ttd_length"`), or the 2024 LoRR winner's pair cost in cells of travel (`"pair_cost"`:
minus `ttd + length / 5`). Only the acting robot is rewarded.

## Termination and truncation

An episode is `num_tasks` decisions. In `episode_mode="drain"` (default) exactly
`num_tasks` tasks are served and every agent *terminates* at once; in `"paper"` mode the
queue is always refilled and every agent is *truncated*. Once every agent has stepped
with `None` and been removed, `last()` still answers for `agent_selection` (the last
agent removed): final observation, reward `0`, the episode's flags and infos.

## Infos

`infos[agent]` holds the episode metrics as flat keys, every field of
`rtaw_marl.sim.metrics.EpisodeMetrics`: `ttd`, `makespan`, `task_length`, `idle_mean`,
`idle_max`, `wait_mean`, `wait_max` (seconds), `tasks_served`, `decisions` (integers).
They are there from `reset()` on, as zeros, so that vectorising wrappers and TorchRL
(whose info spec comes from the reset infos) carry them, and hold the episode's metrics
(`sim.metrics().as_dict()`) once it ends. One dict is shared by every agent (read-only).

## Seeding

`reset(seed=s)` takes `None` or an integer `>= 0` (else `ConfigError`). A seed fixes the
episode (tasks, starts, noise) and reseeds `np_random` (a NumPy `Generator`;
`np_random_seed` is `s`); `reset()` without a seed draws the episode seed from
`np_random`, so a seeded sequence of episodes is reproducible, and never from the seeds
reserved for results (0-1999: evaluation and selection; `rtaw_marl.sim.inputs`).
`env.unwrapped.episode_seed` is the current episode's seed (to replay it).

## Misuse

Every call out of order raises one of the project's errors (`rtaw_marl.errors`), with
what to do in the message: `observe`, `step`, `last`, `state`, `render`, `agent_iter`,
`observe_all`, or reading `agents`, `agent_selection`, `rewards`, ... before the first
`reset()` raise `ResetNeededError` (also an `AttributeError`, as PettingZoo's wrapper
raises for attributes); any call after `close()` raises `EnvUsageError`; an agent
name outside `possible_agents` (`observe`, `observation_space`, `action_space`) raises
`UnknownAgentError` (also a `KeyError`). `reset(options=...)` takes `None` or a dict;
the env has no reset options, so a dict's keys are ignored with a `UserWarning` naming
them (not an error: PettingZoo's own `api_test` passes `{"options": 1}`).

## Rendering

`render_mode="human"` prints the grid as text, `"ansi"` returns it: `.` free, `@`
obstacle, `o` / `d` origin / destination of a queued task, `R` a robot (where it will
next be free), `*` the robot choosing now, then a status line.

## Arguments

`env(layout=None, navigator=None, tasks=None, render_mode=None, observation="full",
obs_format="dict", scenario=None, **sim_keys)`: `scenario` names a setting of
`rtaw_marl.scenarios.SCENARIOS` (as `scenario=NAME` on the command line; the other
arguments override it), `layout="C"` is the paper's layout C as `layout=C` is;
`**sim_keys` are the keys of `SimConfig`, the `sim.*` config keys (`num_robots=10,
num_tasks=500, queue_len=10, episode_mode="drain", noise_mean=0.25, noise_var=0.25,
reward="ttd", robot_starts=None, robot_free_times=None`); an unknown key or option is a
`ConfigError` listing them. `layout` and `tasks` take a name, a `{"name": ..., **keys}`
mapping, a typed option (`rtaw_marl.sim.options`) or an object (`Layout`, `TaskStream`),
`layout` also a file path (default `"shelves"`, `"designated"`). `navigator` is
`"direct"`, `"astar"` (default), or a collision-aware `"sipp"` / `"cbs"` (robots wait
for each other; the reward is the TTD planned at the decision, the metrics count the
executed waits; their tasks are timed by whole-second paths, so they set `noise_mean=0,
noise_var=0` unless given, as `navigator=sipp` does on the command line).

## Version History

* v1 (`rtaw/warehouse-v1`): masked-observation layout `{"observation", "action_mask"}`
  (same feature values), `observation="compact"`, `obs_format="flat"`, `state()`, flat
  metrics in `infos` from `reset()` on (v0: `infos[agent]["episode"]` at the end),
  `render_mode="human"`, `np_random`, `observation_spaces` / `action_spaces`.
* v0: an internal draft, never released (features beside `action_mask` at the top
  level); its module is gone.
* The env family's names (no behaviour change): metadata name `warehouse_v1` (was
  `rtaw_warehouse_v1`), the Gymnasium adapter `rtaw/warehouse-single-v1` (was
  `rtaw/Warehouse-v1`, still made with a `DeprecationWarning`).
"""

from __future__ import annotations

import dataclasses
import warnings
from collections.abc import Mapping
from typing import Any, ClassVar

import numpy as np
from gymnasium import spaces
from gymnasium.utils import seeding
from pettingzoo import AECEnv
from pettingzoo.utils import wrappers

from rtaw_marl import register_envs
from rtaw_marl.decision.observations import AgentViews, Features, ObservationLayout, state_vector
from rtaw_marl.envs.spaces import agent_space, state_space
from rtaw_marl.envs.text import render_ansi
from rtaw_marl.errors import (
    ConfigError,
    EnvUsageError,
    InvalidActionError,
    UnknownAgentError,
    usage_error,
)
from rtaw_marl.scenarios import Scenario
from rtaw_marl.scenarios.merge import spec_with
from rtaw_marl.sim.builder import build_sim
from rtaw_marl.sim.core import WarehouseSim
from rtaw_marl.sim.distances import DistanceModel
from rtaw_marl.sim.inputs import draw_training_seed, seed_value
from rtaw_marl.sim.metrics import EpisodeMetrics
from rtaw_marl.sim.options import LayoutOption, NavigatorOption, TaskOption

__all__ = ["env", "raw_env", "reset_option_keys", "zero_info"]

Observation = dict[str, Any]
Info = dict[str, float | int]

#: Attributes that exist from the first ``reset()`` on (PettingZoo's order-enforced set).
_SET_BY_RESET = frozenset(
    {"agents", "agent_selection", "rewards", "terminations", "truncations", "infos"}
    | {"num_agents", "_cumulative_rewards"}
)


def reset_option_keys(options: object) -> list[str]:
    """The keys of ``reset(options=...)``, which must be ``None`` or a mapping.

    Raises:
        EnvUsageError: ``options`` is neither ``None`` nor a mapping.
    """
    if options is None:
        return []
    if not isinstance(options, Mapping):
        raise EnvUsageError(
            f"reset(options=...) takes a dict or None, got {type(options).__name__} {options!r:.40}"
        )
    return sorted(map(str, options))


def env(**kwargs: Any) -> AECEnv:
    """The warehouse env wrapped in PettingZoo's ``OrderEnforcingWrapper``.

    ``AssertOutOfBoundsWrapper`` is left out on purpose: the raw env already raises a
    clear :class:`~rtaw_marl.errors.InvalidActionError` for any illegal action.
    """
    return _OrderEnforcing(raw_env(**kwargs))


class _OrderEnforcing(wrappers.OrderEnforcingWrapper):
    """``OrderEnforcingWrapper`` whose :meth:`last` is the env's own, and whose calls
    before ``reset()`` raise :class:`~rtaw_marl.errors.ResetNeededError` as the raw env
    does (PettingZoo's raise a bare ``AssertionError`` or ``AttributeError``).

    PettingZoo's ``AECEnv.last`` reads the per-agent tables, which hold live agents only,
    so it raises ``KeyError`` once every agent is removed; :meth:`raw_env.last` answers.
    """

    def __getattr__(self, name: str) -> Any:
        if name in _SET_BY_RESET and not self._has_reset:
            raise usage_error(f"env.{name}")
        return super().__getattr__(name)

    def reset(self, seed: int | None = None, options: dict | None = None) -> None:
        """The wrapper's reset; one that raises leaves the wrapper unreset, as the env."""
        try:
            super().reset(seed=seed, options=options)
        except BaseException:
            self._has_reset = False
            raise

    def _require_reset(self, call: str) -> None:
        if not self._has_reset:
            raise usage_error(call)

    def last(self, observe: bool = True) -> tuple[Observation | None, float, bool, bool, Info]:
        """:meth:`raw_env.last`, after the wrapper's check that ``reset`` was called."""
        self._require_reset("env.last()")
        return self.env.last(observe)

    def step(self, action: int | None) -> None:
        self._require_reset("env.step()")
        super().step(action)

    def observe(self, agent: str) -> Observation:
        self._require_reset("env.observe()")
        return super().observe(agent)

    def state(self) -> np.ndarray:
        self._require_reset("env.state()")
        return super().state()

    def render(self) -> str | None:
        self._require_reset("env.render()")
        return super().render()

    def agent_iter(self, max_iter: int = 2**63) -> Any:
        self._require_reset("env.agent_iter()")
        return super().agent_iter(max_iter)

    def __str__(self) -> str:
        return str(self.env)


def zero_info() -> Info:
    """The infos before an episode ends: every :class:`EpisodeMetrics` field at zero."""
    return {
        f.name: 0 if f.type in ("int", int) else 0.0 for f in dataclasses.fields(EpisodeMetrics)
    }


class raw_env(AECEnv):
    """The unwrapped warehouse AEC environment; see the module docstring."""

    metadata: ClassVar[dict[str, Any]] = {
        "name": "warehouse_v1",
        "render_modes": ["human", "ansi"],
        "is_parallelizable": False,
    }

    def __init__(
        self,
        layout: str | Mapping[str, Any] | LayoutOption | None = None,
        navigator: str | Mapping[str, Any] | NavigatorOption | None = None,
        tasks: str | Mapping[str, Any] | TaskOption | None = None,
        render_mode: str | None = None,
        *,
        observation: str = "full",
        obs_format: str = "dict",
        scenario: str | Scenario | None = None,
        **sim_keys: Any,
    ) -> None:
        """Build the env (see the module docstring, *Arguments*).

        Args:
            layout: A layout name, file path, ``{"name": ..., **keys}`` mapping or typed
                option; ``None``: the default (60x60 shelves).
            navigator: ``"direct"``, ``"astar"`` (default), ``"sipp"``, ``"cbs"`` or a
                mapping/typed option.
            tasks: A task-stream option (default ``"designated"``).
            render_mode: ``None``, ``"human"`` or ``"ansi"``.
            observation: ``"full"`` or ``"compact"`` (no robot table).
            obs_format: ``"dict"`` or ``"flat"`` (one vector).
            scenario: A :data:`~rtaw_marl.scenarios.SCENARIOS` name or a
                :class:`~rtaw_marl.scenarios.Scenario` (``lorr_scenario(path)``: a LoRR
                problem); the groups and keys given here override it.
            **sim_keys: Simulator keys (:class:`~rtaw_marl.sim.config.SimConfig`, the
                ``sim.*`` config keys).

        Raises:
            ConfigError: An unknown or invalid option or key.
        """
        super().__init__()
        # Live from reset() to close(); one flag read is all the hot path pays.
        self._live, self._closed = False, False
        modes = self.metadata["render_modes"]
        if render_mode is not None and render_mode not in modes:
            raise ConfigError(
                f"Unknown render_mode {render_mode!r}. Available: None, {', '.join(modes)}"
            )
        spec = spec_with(scenario, sim_keys, layout, navigator, tasks)
        m, n = spec.sim.num_robots, spec.sim.queue_len
        self.obs_layout = ObservationLayout(observation, obs_format, m, n)
        self.sim: WarehouseSim = build_sim(spec)
        self.render_mode = render_mode
        self.scale = self.sim.layout.scale
        self.possible_agents = [f"robot_{i}" for i in range(m)]
        self._index = {name: i for i, name in enumerate(self.possible_agents)}
        # One space object per kind: every agent's spaces are identical.
        self.observation_spaces = dict.fromkeys(
            self.possible_agents, agent_space(self.obs_layout, self.sim.config.reassign)
        )
        self.action_spaces = dict.fromkeys(self.possible_agents, spaces.Discrete(n))
        self.state_space = state_space(self.obs_layout)
        self.np_random, self.np_random_seed = seeding.np_random()
        self._views = AgentViews(self.sim, self.obs_layout)

    @property
    def distance_model(self) -> DistanceModel:
        """The simulator's distance model (RBTS uses it to measure other robots'
        distances)."""
        return self.sim.distance_model

    @property
    def navigator(self) -> DistanceModel:
        """Deprecated alias of :attr:`distance_model` (the ``navigator`` argument is the
        option; this is its distance model only)."""
        warnings.warn(
            "warehouse_v1 env.navigator is deprecated, use .distance_model",
            DeprecationWarning,
            stacklevel=2,
        )
        return self.sim.distance_model

    def __getattr__(self, name: str) -> Any:
        # Python calls this only when normal lookup fails, so live reads pay nothing.
        if name in _SET_BY_RESET:
            raise usage_error(f"env.{name}")
        raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")

    def _unknown(self, agent: object) -> UnknownAgentError:
        names = [repr(name) for name in self.possible_agents]
        if len(names) > 4:
            names = [names[0], names[1], "...", names[-1]]
        return UnknownAgentError(f"unknown agent {agent!r}; the agents are {', '.join(names)}")

    def observation_space(self, agent: str) -> spaces.Dict:
        try:
            return self.observation_spaces[agent]
        except (KeyError, TypeError):
            raise self._unknown(agent) from None

    def action_space(self, agent: str) -> spaces.Discrete:
        try:
            return self.action_spaces[agent]
        except (KeyError, TypeError):
            raise self._unknown(agent) from None

    # ------------------------------------------------------------------ reset
    def reset(self, seed: int | None = None, options: dict | None = None) -> None:
        """Start an episode; ``seed`` fixes tasks, starts and noise and reseeds
        ``np_random``; without a seed the episode seed is drawn from ``np_random``, outside
        the reserved seeds 0-1999.

        ``options`` is ``None`` or a dict; the env takes no options, so a dict's keys are
        ignored with a ``UserWarning`` (PettingZoo's ``api_test`` passes a dummy key).

        Raises:
            ConfigError: ``seed`` is neither ``None`` nor an integer ``>= 0``.
            EnvUsageError: ``options`` is not a dict, or the env is closed.
        """
        if self._closed:
            raise usage_error("env.reset()", self._closed)
        # Not live until the new episode is built: a reset that raises leaves none to step.
        self._live = False
        if keys := reset_option_keys(options):
            warnings.warn(
                f"reset options {keys} ignored: warehouse_v1's reset takes no options",
                stacklevel=2,
            )
        if seed is not None:
            seed = seed_value(seed)
            self.np_random, self.np_random_seed = seeding.np_random(seed)
            episode_seed = seed
        else:
            episode_seed = draw_training_seed(self.np_random)
        self.sim.reset(episode_seed)
        self.episode_seed = episode_seed
        self._views.clear()
        self.agents = self.possible_agents[:]
        self.rewards = dict.fromkeys(self.agents, 0.0)
        self._cumulative_rewards = dict.fromkeys(self.agents, 0.0)
        self.terminations = dict.fromkeys(self.agents, False)
        self.truncations = dict.fromkeys(self.agents, False)
        self._final_info = zero_info()
        self.infos = dict.fromkeys(self.agents, self._final_info)
        self._last_actor = self.possible_agents[0]
        self.agent_selection = self.possible_agents[self.sim.robot]
        self._live = True

    def close(self) -> None:
        """End the env's use: every later call raises :class:`EnvUsageError`."""
        self._live, self._closed = False, True

    # ------------------------------------------------------------------ observe
    def observe(self, agent: str) -> Observation:
        """``{"observation": features, "action_mask": int8 [N]}`` (module docstring).

        Raises:
            UnknownAgentError: ``agent`` is not in ``possible_agents``.
            EnvUsageError: Before ``reset()`` (:class:`ResetNeededError`) or after ``close()``.
        """
        if not self._live:
            raise usage_error("env.observe()", self._closed)
        try:
            index = self._index[agent]
        except (KeyError, TypeError):
            raise self._unknown(agent) from None
        return self._views.observe(index)

    def observe_all(self) -> dict[str, Features]:
        """Every agent's observation at once, in ``possible_agents`` order.

        Returns:
            ``{"observation": features, "action_mask": int8 [M, N]}``, the features
            stacked over robots (``[M, ...]`` per key, or ``[M, flat_size]``); row ``i``
            equals ``observe(possible_agents[i])``. Shared until the next decision.
        """
        if not self._live:
            raise usage_error("env.observe_all()", self._closed)
        features, masks = self._views.observe_all()
        return {"observation": features, "action_mask": masks}

    def state(self) -> np.ndarray:
        """The global state ``float32 [3M + 7N]``: robot table, then queue rows."""
        if not self._live:
            raise usage_error("env.state()", self._closed)
        return state_vector(self.sim)

    # ------------------------------------------------------------------ step
    def step(self, action: int | None) -> None:
        """Give queue slot ``action`` to the selected robot (``None``: remove a done agent).

        Raises:
            InvalidActionError: ``action`` is not a valid slot of a live agent or ``None``
                for a done one, or every agent is already removed; the env is unchanged.
            EnvUsageError: Before ``reset()`` (:class:`ResetNeededError`) or after ``close()``.
        """
        if not self._live:
            raise usage_error("env.step()", self._closed)
        agent = self.agent_selection
        terminated = self.terminations.get(agent)
        if terminated is None:
            raise InvalidActionError("the episode is over and every agent removed; call reset()")
        if terminated or self.truncations[agent]:
            self._dead_step(action)
            return
        if action is None:
            raise InvalidActionError(
                f"{agent} is not done; its action must be a queue slot "
                f"(0..{self.sim.queue_len - 1}), got None (None is only for a done agent)"
            )
        sim = self.sim
        self._cumulative_rewards[agent] = 0.0
        reward = sim.step(action)
        # Only the acting robot is rewarded: clear the previous actor's entry, O(1).
        self.rewards[self._last_actor] = 0.0
        self.rewards[agent] = reward
        self._cumulative_rewards[agent] += reward
        self._last_actor = agent
        if sim.done:
            self._end_episode()
            # The last actor goes first in the dead phase, so it sees its final reward.
            self.agent_selection = agent
        else:
            self.agent_selection = self.possible_agents[sim.robot]

    def _end_episode(self) -> None:
        sim = self.sim
        done = dict.fromkeys(self.agents, True)
        if sim.truncated:
            self.truncations = done
        else:
            self.terminations = done
        self._final_info = sim.metrics().as_dict()
        self.infos = dict.fromkeys(self.agents, self._final_info)

    def _dead_step(self, action: int | None) -> None:
        """Remove the selected finished agent; all agents finish together, in id order."""
        agent = self.agent_selection
        if action is not None:
            raise InvalidActionError(
                f"{agent} is done; its only valid action is None, got {action!r}"
            )
        tables = (self.terminations, self.truncations, self.rewards, self._cumulative_rewards)
        for table in (*tables, self.infos):
            del table[agent]
        self.agents.remove(agent)
        if self.agents:
            self.agent_selection = self.agents[0]

    def last(self, observe: bool = True) -> tuple[Observation | None, float, bool, bool, Info]:
        """``AECEnv.last``; once every agent is removed (the per-agent tables are empty),
        the final observation of ``agent_selection`` (the last agent removed), reward 0
        (handed out before its removal), the episode's flags and infos."""
        if not self._live:
            raise usage_error("env.last()", self._closed)
        agent = self.agent_selection
        if agent in self.terminations:
            return super().last(observe)
        truncated = self.sim.truncated
        observation = self.observe(agent) if observe else None
        return observation, 0.0, not truncated, truncated, self._final_info

    # ------------------------------------------------------------------ render
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
