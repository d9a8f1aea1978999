"""# RTAW Warehouse (``rtaw_warehouse_v0``)

Lifelong multi-robot task allocation in a warehouse grid (the RTAW paper's MDP) as a
PettingZoo AEC environment. Whenever a robot becomes free it is the acting agent and
picks one task from a queue of ``N`` visible tasks; its cost is the empty travel to the
task's pickup (the *travel delay*).

| Import             | `from rtaw_marl import warehouse_v0`                    |
|--------------------|---------------------------------------------------------|
| Actions            | Discrete                                                |
| Parallel API       | No (one robot acts at a time)                           |
| Manual control     | No                                                      |
| Agents             | `agents = ['robot_0', ..., 'robot_{M-1}']`              |
| Number of agents   | `num_robots` (M)                                        |
| Action shape       | `()`                                                    |
| Action values      | `Discrete(queue_len)`                                   |
| Observation shape  | dict of arrays (see Observation below)                  |
| Observation values | float32, roughly in `[0, 1]` (see scales)               |

## Agents and turn order

`agent_selection` is always the robot that becomes free next (the one with the
smallest free time; ties go to the lowest robot id). It picks a task, travels to the
task's origin and on to its destination, and becomes free again at completion time plus
Gaussian noise (`noise_mean`, `noise_var`). Decisions happen at irregular times, so
the same robot may act several times in a row.

## Observation

A dict per agent, all float32 except the mask. Lengths and times are divided by the
layout scale `L = max(W, H)` (robots move one cell per second, so times and distances
share the scale); coordinates use `x` = column, `y` = row.

* `robots` `[M, 3]`: for every robot, `(x / L, y / L, time_until_free / L)`. The cell
  is where the robot will be when next free (its current task's destination). The same
  array object is shared by all agents' observations of one decision; copy it before
  modifying it.
* `tasks` `[N, 6]`: for every queue slot, `(ox, oy, dx, dy, k, l) / L`: origin,
  destination, `k` the travel distance from *this* robot to the origin and `l` the
  task length (origin -> destination). Empty slots (possible at the end of a `drain`
  episode) are all zeros.
* `agent` `[3]`: this robot's own row of `robots`.
* `relations` `[N, 8]`: relational features of each slot from *this* robot's point of
  view (read by `model=rtaw_plus`), all divided by `L`: its distance `k` to the origin,
  the task length, the time the task has waited in the queue, the arrival of the three
  fastest rivals minus `k`, a soft-min (temperature `0.05 L`) of the rivals' arrivals
  minus `k`, and the distance from the task's destination to the nearest other queued
  origin. A robot's *arrival* is its time until free plus the distance from the cell
  where it will be free; *rivals* are the other robots. A missing rival or chain
  partner counts as `2` (two layout scales away).
* `rivals` `[N, 8, 4]`: per slot, the 8 rivals arriving first (sorted; ties: lowest
  robot id), each `(arrival - k, time_until_free, distance) / L` and a validity flag
  (0 for the padding rows when there are fewer than 9 robots).
* `action_mask` `[N]` int8: 1 for the slots holding a task. The mask of any agent other
  than the selected one is all zeros.

## Actions

The index of a queue slot: a Python or NumPy integer (or a 0-d integer array). The
chosen slot is refilled from the task stream. Anything else raises
`rtaw_marl.errors.InvalidActionError` and leaves the env as it was (nothing is silently
fixed): an out-of-range or empty slot, a float (even `1.0`), a bool, a string, an array
of shape other than `()`, or `None` for a live agent. `None` is the only valid action of
a terminated or truncated agent.

## Rewards

Minus the travel delay of the chosen task (`reward="ttd"`, the paper's reward), or for
the paper's ablation minus the task length (`"length"`) or their sum
(`"ttd_length"`). Only the acting robot is rewarded.

## Termination and truncation

An episode is `num_tasks` decisions. In `episode_mode="drain"` (default) exactly
`num_tasks` tasks are served and the episode *terminates*; in `"paper"` mode the queue
is always refilled, unserved tasks remain at the end, and the episode is *truncated*.
Then every agent is terminated (or truncated) at once, and `infos[agent]["episode"]`
holds the episode metrics (`ttd`, `makespan`, ...). Once every agent has stepped with
`None` and been removed, `last()` still answers for `agent_selection` (the last agent
removed): its final observation, reward `0`, the episode's termination and truncation
flags, and the episode info.

## Seeding

`reset(seed=s)` takes `None` or an integer `>= 0` (Python or NumPy); anything else (a
negative or float seed, a bool, a string) raises `rtaw_marl.errors.ConfigError`.

## Arguments

`env(layout=None, navigator=None, tasks=None, render_mode=None, **env)`: the simulator
keys `**env` are those of `SimConfig` (`num_robots=10, num_tasks=500, queue_len=10,
episode_mode="drain", noise_mean=0.25, noise_var=0.25, reward="ttd", robot_starts=None,
robot_free_times=None`; an unknown key is an error listing them). `layout` and `tasks`
take an option name, a `{"name": ..., **keys}` mapping, a typed option
(`rtaw_marl.sim.options`) or an object (`Layout`, `TaskStream`); `layout` also takes a
file path; `None` means the default (`"shelves"`, `"designated"`). `navigator` is
`"direct"`, `"astar"` (default), or a collision-aware `"sipp"` / `"cbs"` (or `{"name":
"cbs", "time_limit": 5}`): robots then occupy cells and wait for each other, the reward
is the TTD planned at the decision and the episode metrics count the executed waits;
these need `noise_mean=0, noise_var=0`. `render_mode="ansi"` returns the grid as text.

## Version History

* v0: initial release.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, ClassVar

import numpy as np
from gymnasium import spaces
from pettingzoo import AECEnv
from pettingzoo.utils import wrappers

from rtaw_marl import register_envs
from rtaw_marl.envs.features import (
    NUM_RIVALS,
    RELATION_FEATURES,
    RIVAL_FEATURES,
    relational_features,
    robot_features,
    task_features,
)
from rtaw_marl.envs.text import render_ansi
from rtaw_marl.errors import InvalidActionError
from rtaw_marl.sim.builder import SimSpec, build_sim
from rtaw_marl.sim.core import WarehouseSim
from rtaw_marl.sim.inputs import seed_value
from rtaw_marl.sim.navigation import Navigator
from rtaw_marl.sim.options import LayoutOption, NavigatorOption, TaskOption

__all__ = ["env", "raw_env"]


def env(**kwargs: Any) -> AECEnv:
    """The warehouse env wrapped in PettingZoo's ``OrderEnforcingWrapper``.

    ``AssertOutOfBoundsWrapper`` is left out on purpose: the raw env already raises a
    clear :class:`~rtaw_marl.errors.InvalidActionError` for any illegal action.
    """
    return _OrderEnforcing(raw_env(**kwargs))


class _OrderEnforcing(wrappers.OrderEnforcingWrapper):
    """``OrderEnforcingWrapper`` whose :meth:`last` is the env's own.

    PettingZoo's ``AECEnv.last`` reads the per-agent tables, which hold live agents only,
    so it raises ``KeyError`` once every agent is removed; :meth:`raw_env.last` answers.
    """

    def last(
        self, observe: bool = True
    ) -> tuple[dict[str, np.ndarray] | None, float, bool, bool, dict[str, Any]]:
        """:meth:`raw_env.last`, after the wrapper's check that ``reset`` was called."""
        if not self._has_reset:
            raise AttributeError("last() cannot be called before reset()")
        return self.env.last(observe)

    def __str__(self) -> str:
        return str(self.env)


class raw_env(AECEnv):
    """The unwrapped warehouse AEC environment; see the module docstring."""

    metadata: ClassVar[dict[str, Any]] = {
        "name": "rtaw_warehouse_v0",
        "render_modes": ["ansi"],
        "is_parallelizable": False,
    }

    def __init__(
        self,
        layout: str | Mapping[str, Any] | LayoutOption | None = None,
        navigator: str | Mapping[str, Any] | NavigatorOption | None = None,
        tasks: str | Mapping[str, Any] | TaskOption | None = None,
        render_mode: str | None = None,
        **env: Any,
    ) -> None:
        """Build the env.

        Args:
            layout: A layout option: a name (``"shelves"``, ``"A"`` is ``{"name":
                "preset", "preset": "A"}``), a file path, a ``{"name": ..., **keys}``
                mapping or a typed option; ``None``: the default (60x60 shelves).
            navigator: ``"direct"``, ``"astar"`` (default), ``"sipp"``, ``"cbs"``, or a
                mapping/typed option with their keys.
            tasks: A task-stream option (default ``"designated"``).
            render_mode: ``None`` or ``"ansi"``.
            **env: Simulator keys (:class:`~rtaw_marl.sim.config.SimConfig`:
                ``num_robots``, ``num_tasks``, ``queue_len``, ``episode_mode``,
                ``noise_mean``, ``noise_var``, ``reward``, ``robot_starts``,
                ``robot_free_times``); an unknown key is a ``ConfigError`` listing them.
        """
        super().__init__()
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"render_mode must be None or 'ansi', got {render_mode!r}")
        spec = SimSpec.of(env, layout, navigator, tasks)
        config = spec.env
        self.sim: WarehouseSim = build_sim(spec)
        self.render_mode = render_mode
        self.scale = self.sim.layout.scale
        m, n = config.num_robots, config.queue_len
        self.possible_agents = [f"robot_{i}" for i in range(m)]
        self._index = {name: i for i, name in enumerate(self.possible_agents)}
        inf = np.float32(np.inf)
        self._observation_space = spaces.Dict(
            {
                "robots": spaces.Box(0.0, np.array([[1, 1, inf]] * m, np.float32), (m, 3)),
                "tasks": spaces.Box(
                    0.0, np.array([[1, 1, 1, 1, inf, inf]] * n, np.float32), (n, 6)
                ),
                "agent": spaces.Box(0.0, np.array([1, 1, inf], np.float32), (3,)),
                # Rival offsets are negative when a rival arrives first.
                "relations": spaces.Box(-inf, inf, (n, len(RELATION_FEATURES)), np.float32),
                "rivals": spaces.Box(-inf, inf, (n, NUM_RIVALS, len(RIVAL_FEATURES)), np.float32),
                "action_mask": spaces.Box(0, 1, (n,), np.int8),
            }
        )
        self._action_space = spaces.Discrete(n)
        self._seed_rng = np.random.default_rng()
        self._zero_mask = np.zeros(n, dtype=np.int8)

    @property
    def navigator(self) -> Navigator:
        """The simulator's navigator (RBTS uses it to measure other robots' distances)."""
        return self.sim.navigator

    def observation_space(self, agent: str) -> spaces.Dict:
        return self._observation_space

    def action_space(self, agent: str) -> spaces.Discrete:
        return self._action_space

    # ------------------------------------------------------------------ reset
    def reset(self, seed: int | None = None, options: dict | None = None) -> None:
        """Start an episode; ``seed`` fixes tasks, starts and noise.

        Without a seed, the episode seed is drawn from a generator seeded by the last
        explicit seed, so a seeded sequence of episodes is reproducible.

        Raises:
            ConfigError: ``seed`` is neither ``None`` nor an integer ``>= 0``.
        """
        if seed is not None:
            seed = seed_value(seed)
            self._seed_rng = np.random.default_rng(seed)
            episode_seed = seed
        else:
            episode_seed = int(self._seed_rng.integers(2**63))
        self.sim.reset(episode_seed)
        self.agents = self.possible_agents[:]
        self.rewards = dict.fromkeys(self.agents, 0.0)
        self._cumulative_rewards = dict.fromkeys(self.agents, 0.0)
        self.terminations = dict.fromkeys(self.agents, False)
        self.truncations = dict.fromkeys(self.agents, False)
        self.infos = {agent: {} for agent in self.agents}
        self._last_actor = self.possible_agents[0]
        self._cache_decision = -1
        self.agent_selection = self.possible_agents[self.sim.robot]

    # ------------------------------------------------------------------ observe
    def observe(self, agent: str) -> dict[str, np.ndarray]:
        robot = self._index[agent]
        sim = self.sim
        self._refresh_cache()
        if robot == sim.robot and not sim.done:
            distance, mask = sim.robot_distances(), self._mask
        else:
            distance, mask = sim.robot_distances(robot), self._zero_mask.copy()
        relations, rivals = relational_features(
            self._all_dist, self._remaining, robot, sim.queue_length, self._waits,
            self._chain, sim.queue_mask, self.scale,
        )  # fmt: skip
        return {
            "robots": self._robot_rows,
            "tasks": task_features(
                sim.queue_rows, sim.queue_length, distance, sim.queue_mask, self.scale
            ),
            "agent": self._robot_rows[robot].copy(),
            "relations": relations,
            "rivals": rivals,
            "action_mask": mask,
        }

    def _refresh_cache(self) -> None:
        """Per-decision robot features shared by all agents' observations."""
        sim = self.sim
        if self._cache_decision == sim.decisions:
            return
        self._robot_rows = robot_features(sim.robot_xy, sim.robot_free_at, sim.time, self.scale)
        self._mask = sim.queue_mask.astype(np.int8)
        self._all_dist = sim.distance_matrix()
        self._remaining = sim.robot_remaining()
        self._waits = sim.queue_waits()
        self._chain = sim.chain_distances()
        self._cache_decision = sim.decisions

    # ------------------------------------------------------------------ step
    def step(self, action: int | None) -> None:
        """Give queue slot ``action`` to the selected robot (``None``: remove a done agent).

        Raises:
            InvalidActionError: ``action`` is not a valid slot of a live agent or ``None``
                for a done one, or every agent is already removed; the env is unchanged.
        """
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
        self._final_info = {"episode": sim.metrics().as_dict()}
        self.infos = dict.fromkeys(self.agents, self._final_info)

    def _dead_step(self, action: int | None) -> None:
        """Remove the selected finished agent; all agents finish together, in id order."""
        agent = self.agent_selection
        if action is not None:
            raise InvalidActionError(
                f"{agent} is done; its only valid action is None, got {action!r}"
            )
        for table in (
            self.terminations,
            self.truncations,
            self.rewards,
            self._cumulative_rewards,
            self.infos,
        ):
            del table[agent]
        self.agents.remove(agent)
        if self.agents:
            self.agent_selection = self.agents[0]

    def last(
        self, observe: bool = True
    ) -> tuple[dict[str, np.ndarray] | None, float, bool, bool, dict[str, Any]]:
        """Observation, cumulative reward, terminated, truncated and info of
        ``agent_selection``, as ``AECEnv.last``.

        Once every agent has been removed (the per-agent tables are empty), the answer
        for ``agent_selection``, the last agent removed, is its final observation, reward
        0 (its reward was handed out before its removal), the episode's flags and info.
        """
        agent = self.agent_selection
        if agent in self.terminations:
            return super().last(observe)
        truncated = self.sim.truncated
        observation = self.observe(agent) if observe else None
        return observation, 0.0, not truncated, truncated, self._final_info

    # ------------------------------------------------------------------ render
    def render(self) -> str | None:
        if self.render_mode is None:
            return None
        return render_ansi(self.sim)

    def close(self) -> None:
        pass


register_envs()
