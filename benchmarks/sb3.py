"""SB3-contrib's ``MaskablePPO`` on the Gymnasium adapter: the settings under which it
learns (docs/integrations.md, "A MaskablePPO recipe that learns").

Out of the box (``gamma=0.99``, rewards in seconds) ``MaskablePPO`` stays near random
within 32k steps. The reason is the discount, not the features (already divided by the
layout scale): an episode is ``num_tasks`` decisions of every robot, so with
``gamma=0.99`` each decision's advantage carries the costs of about a hundred later
decisions, mostly other robots', and the policy gradient of its own cost drowns in them.
The total travel delay is a sum of per-decision costs, so ``gamma=0`` makes each decision
a contextual bandit on its own cost: PPO then learns in a few thousand decisions. The
reward is also divided by the layout scale ``L`` (rewards in the features' units, so the
value loss stays near 1). With ``gamma=0`` the best policy minimises each decision's own
travel delay, which is what MPDM does: the recipe reaches MPDM, not beyond it.

SB3's ``seed=s`` also seeds the envs' first resets with ``s + i``; :func:`make_model`
passes a training seed, so no training episode is an evaluation or selection one.

Importing this module imports ``sb3_contrib`` (``pip install sb3-contrib``).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, SupportsFloat

import gymnasium
import numpy as np
from sb3_contrib import MaskablePPO
from stable_baselines3.common.env_util import make_vec_env

import rtaw_marl.envs.gymnasium  # noqa: F401  (registers the adapter's id)
from rtaw_marl import GYMNASIUM_ENV_ID
from rtaw_marl.errors import ConfigError
from rtaw_marl.policies import make_baseline
from rtaw_marl.sim.inputs import seed_list, training_seed

__all__ = [
    "RECIPE",
    "Sb3Recipe",
    "ScaledReward",
    "evaluate_model",
    "make_model",
    "make_sb3_env",
    "rule_ttds",
]


class ScaledReward(gymnasium.RewardWrapper):
    """Divides the reward by the layout scale ``L = max(W, H)``: a decision's reward
    becomes minus its travel delay in layout scales, the unit of the features.
    ``info["ttd"]`` stays in cells."""

    def __init__(self, env: gymnasium.Env) -> None:
        super().__init__(env)
        self.scale = float(env.unwrapped.sim.layout.scale)

    def reward(self, reward: SupportsFloat) -> float:
        """``reward / L``."""
        return float(reward) / self.scale


@dataclass(frozen=True)
class Sb3Recipe:
    """``MaskablePPO`` settings that learn on the warehouse (the module docstring says why).

    Attributes:
        gamma: Discount; 0 makes each decision a bandit on its own travel delay.
        gae_lambda: GAE's lambda (no effect at ``gamma=0``).
        n_steps: Decisions collected per env between updates.
        batch_size: Minibatch size.
        n_epochs: Passes over each rollout.
        learning_rate: Adam's step size.
        ent_coef: Entropy bonus; 0, as masking already keeps exploration among legal slots.
        net_arch: Hidden sizes of the policy and value MLPs (separate networks).
        scale_reward: Divide rewards by the layout scale (:class:`ScaledReward`).
    """

    gamma: float = 0.0
    gae_lambda: float = 0.95
    n_steps: int = 2048
    batch_size: int = 64
    n_epochs: int = 10
    learning_rate: float = 3e-4
    ent_coef: float = 0.0
    net_arch: tuple[int, ...] = (64, 64)
    scale_reward: bool = True

    def with_overrides(self, **overrides: Any) -> Sb3Recipe:
        """A copy with some settings changed.

        Raises:
            ConfigError: An unknown setting (the message lists the known ones).
        """
        known = [f.name for f in dataclasses.fields(self)]
        if unknown := sorted(set(overrides) - set(known)):
            raise ConfigError(
                f"Unknown recipe setting(s) {', '.join(unknown)}. Available: {', '.join(known)}"
            )
        return dataclasses.replace(self, **overrides)

    def ppo_kwargs(self) -> dict[str, Any]:
        """The keyword arguments of ``MaskablePPO`` these settings stand for."""
        return {
            "gamma": self.gamma,
            "gae_lambda": self.gae_lambda,
            "n_steps": self.n_steps,
            "batch_size": self.batch_size,
            "n_epochs": self.n_epochs,
            "learning_rate": self.learning_rate,
            "ent_coef": self.ent_coef,
            "policy_kwargs": {"net_arch": list(self.net_arch)},
        }


#: The shipped settings.
RECIPE = Sb3Recipe()


def make_sb3_env(scale_reward: bool = True, **env: Any) -> gymnasium.Env:
    """The adapter for SB3: ``gymnasium.make("rtaw/warehouse-single-v1", **env)`` with
    ``observation="compact"`` unless given (its size does not grow with the fleet) and,
    with ``scale_reward``, :class:`ScaledReward` on top.

    Raises:
        ConfigError: An unknown or invalid env key or option.
    """
    made = gymnasium.make(GYMNASIUM_ENV_ID, **{"observation": "compact", **env})
    return ScaledReward(made) if scale_reward else made


def make_model(
    env: dict[str, Any],
    recipe: Sb3Recipe = RECIPE,
    seed: int = 0,
    n_envs: int = 1,
    verbose: int = 0,
) -> MaskablePPO:
    """A ``MaskablePPO`` on ``n_envs`` copies of :func:`make_sb3_env` ``(**env)``.

    Training episodes use training seeds only: the first reset of copy ``i`` takes
    ``training_seed(seed) + i`` and later resets draw theirs from the env's generator,
    never a seed reserved for evaluation or selection (``rtaw_marl.sim.inputs``).

    Raises:
        ConfigError: An unknown env key or a negative ``seed``.
    """
    vec = make_vec_env(
        make_sb3_env, n_envs=n_envs, env_kwargs={"scale_reward": recipe.scale_reward, **env}
    )
    # MaskablePPO(seed=s) also seeds the envs' first resets with s + i (SB3's
    # set_random_seed): s must be a training seed, or they play evaluation episodes.
    return MaskablePPO(
        "MlpPolicy",
        vec,
        seed=training_seed(seed),
        device="cpu",
        verbose=verbose,
        **recipe.ppo_kwargs(),
    )


def evaluate_model(model: MaskablePPO, env: dict[str, Any], seeds: Sequence[int]) -> list[float]:
    """The total travel delay of ``model``'s deterministic masked choices, one episode
    per seed (the same episodes as ``rtaw-eval`` and the rules on these seeds).

    Raises:
        ConfigError: An unknown env key or an invalid seed list.
    """

    def choose(play: gymnasium.Env, obs: np.ndarray, info: dict[str, Any]) -> int:
        action, _ = model.predict(obs, action_masks=info["action_mask"] == 1, deterministic=True)
        return int(action)

    return _play(make_sb3_env(**env), seeds, choose)


def rule_ttds(rule: str, env: dict[str, Any], seeds: Sequence[int]) -> list[float]:
    """The total travel delay of a hand-written rule (``"mpdm"``, ``"random"``, ...) on the
    same episodes as :func:`evaluate_model`.

    Raises:
        ConfigError: An unknown rule or env key, or an invalid seed list.
    """
    play = make_sb3_env(**env)
    policy = make_baseline(rule, env=play)

    def choose(play: gymnasium.Env, obs: np.ndarray, info: dict[str, Any]) -> int:
        return policy.act_sim(play.unwrapped.sim)

    return _play(play, seeds, choose, reset=policy.reset)


def _play(
    play: gymnasium.Env,
    seeds: Sequence[int],
    choose: Callable[[gymnasium.Env, np.ndarray, dict[str, Any]], int],
    reset: Callable[[int], None] | None = None,
) -> list[float]:
    ttds = []
    for seed in seed_list(list(seeds)):
        if reset is not None:
            reset(seed)  # the rule's tie-breaking stream, as rtaw-eval seeds it
        obs, info = play.reset(seed=seed)
        done = False
        while not done:
            obs, _, terminated, truncated, info = play.step(choose(play, obs, info))
            done = terminated or truncated
        ttds.append(float(info["ttd"]))
    play.close()
    return ttds
