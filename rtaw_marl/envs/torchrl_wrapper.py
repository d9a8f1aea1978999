"""TorchRL's ``PettingZooWrapper`` for ``warehouse_v1``, every robot's row at once.

The stock :class:`torchrl.envs.PettingZooWrapper` fills its ``[M, ...]`` output one agent
at a time: per agent and step it indexes the stacked observation spec (which builds a
new spec), encodes the observation, creates a tensor for each reward, done flag and info
value, and deep-copies every observation to strip its action mask. With all robots in
one group that is ``O(M)`` Python work per step whatever the env costs: about 30 ms of a
32 ms step at ``M = 100``, and 135 ms at ``M = 1000`` for an env that does nothing
(``benchmarks/scripts/bench_wrapper.py``).

:class:`WarehouseWrapper` is a ``PettingZooWrapper`` (same specs, keys, group and
semantics) whose ``reset`` and ``step`` fill each key for all robots with one copy, from
the env's :meth:`~rtaw_marl.envs.pettingzoo.raw_env.observe_all` and its reward and
done tables. Its output is bit-identical to the stock wrapper's, step by step
(``tests/envs/test_torchrl_wrapper.py``). It fixes the layout the interop route uses:
all robots in one group ``"agents"``, ``use_mask=True``, categorical actions.

Usage::

    from rtaw_marl import warehouse_v1
    from rtaw_marl.envs.torchrl_wrapper import WarehouseWrapper

    env = WarehouseWrapper(warehouse_v1.env(num_robots=1000, observation="compact"), seed=0)
    td = env.reset()  # td["agents", "observation", "observation", "tasks"]: [1000, N, 6]
"""

from __future__ import annotations

import warnings

import numpy as np
from pettingzoo import AECEnv

from rtaw_marl.errors import missing_extra

# Without the training extra: one error that names it (errors.missing_extra), no traceback
# of a bare ModuleNotFoundError.
try:
    import torch
    from tensordict import TensorDictBase
    from torchrl.envs import PettingZooWrapper
    from torchrl.envs.libs.pettingzoo import MarlGroupMapType
except ModuleNotFoundError as exc:
    raise missing_extra(exc, __name__, "train") from None

from rtaw_marl.decision.observations import Features
from rtaw_marl.envs.pettingzoo import raw_env
from rtaw_marl.sim.inputs import training_seed

__all__ = ["GROUP", "WarehouseWrapper"]

#: The one group every robot belongs to (``MarlGroupMapType.ALL_IN_ONE_GROUP``).
GROUP = "agents"


class WarehouseWrapper(PettingZooWrapper):
    """``PettingZooWrapper(env, use_mask=True, group_map=ALL_IN_ONE_GROUP)``, vectorised.

    Args:
        env: A ``warehouse_v1`` AEC env (``warehouse_v1.env(...)``, wrapped or raw).
        return_state: Also put ``state()`` (``float32 [3M + 7N]``) at the root, key
            ``"state"``.
        seed: Seed of the first reset.
        device: Device of the output tensors (default CPU).
        training: Map every seed given to the wrapper (``seed``, ``set_seed``) through
            :func:`~rtaw_marl.sim.inputs.training_seed`, so that no episode it plays is
            an evaluation or selection episode (seeds 0-1999); what training routes use.

    Raises:
        TypeError: ``env`` is not the warehouse env.
    """

    def __init__(
        self,
        env: AECEnv,
        *,
        return_state: bool = False,
        seed: int | None = None,
        device: torch.device | str | None = None,
        training: bool = False,
    ) -> None:
        if not isinstance(getattr(env, "unwrapped", None), raw_env):
            raise TypeError(
                "WarehouseWrapper wraps the warehouse_v1 env (warehouse_v1.env(...)), "
                f"got {type(env).__name__}; use torchrl's PettingZooWrapper for other envs"
            )
        self._training_seeds = training  # before super().__init__, which seeds
        with warnings.catch_warnings():
            # The wrapper warns on any PettingZoo but the one torchrl is tested with; the
            # range this package supports is covered by its interop tests.
            warnings.filterwarnings(
                "ignore", message=r"PettingZoo in TorchRL is tested using", category=UserWarning
            )
            super().__init__(
                env,
                return_state=return_state,
                group_map=MarlGroupMapType.ALL_IN_ONE_GROUP,
                use_mask=True,
                categorical_actions=True,
                seed=training_seed(seed) if training and seed is not None else seed,
                device=device,
            )

    def _set_seed(self, seed: int | None) -> None:
        if self._training_seeds and seed is not None:
            seed = training_seed(seed)
        super()._set_seed(seed)

    @property
    def _raw(self) -> raw_env:
        return self._env.unwrapped

    def _reset(self, tensordict: TensorDictBase | None = None, **kwargs: object) -> TensorDictBase:
        if tensordict is not None:
            partial = tensordict.get("_reset", None)
            if partial is not None and not partial.all():
                raise RuntimeError(
                    f"{type(self).__name__} resets all robots at once, got {partial}"
                )
        self._env.reset(**kwargs)
        return self._fill(self.cached_reset_output_zero.clone(), step=False)

    def _step(self, tensordict: TensorDictBase) -> TensorDictBase:
        raw = self._raw
        acting = raw.possible_agents.index(raw.agent_selection)
        action_spec = self.input_spec["full_action_spec", GROUP, "action"]
        action = action_spec.to_numpy(tensordict.get((GROUP, "action")))[acting]
        self._env.step(action)
        out = self._fill(self.cached_step_output_zero.clone(), step=True)
        done, terminated, truncated = self._aggregate_done(out, use_any=self.done_on_any)
        out.set("done", done)
        out.set("terminated", terminated)
        out.set("truncated", truncated)
        return out

    def _fill(self, out: TensorDictBase, step: bool) -> TensorDictBase:
        """Write the env's current outputs into the zeroed ``out``, one copy per key."""
        raw = self._raw
        num_robots = len(raw.possible_agents)
        acting = raw.possible_agents.index(raw.agent_selection)
        group = out.get(GROUP)
        # Only the robot choosing next acts: its row alone counts in the loss.
        agent_mask = group.get("mask")
        agent_mask[acting] = True
        # Non-acting rows get an all-True action mask, as the stock wrapper gives them.
        observation = raw.observe_all()
        action_mask = group.get("action_mask")
        action_mask.fill_(True)
        action_mask[acting] = torch.from_numpy(observation["action_mask"][acting].astype(bool))
        self.input_spec["full_action_spec", GROUP, "action"].update_mask(action_mask.clone())
        _copy_features(group.get(("observation", "observation")), observation["observation"])
        if step:
            rewards = np.fromiter(raw.rewards.values(), np.float32, count=num_robots)
            terminated = np.fromiter(raw.terminations.values(), bool, count=num_robots)
            truncated = np.fromiter(raw.truncations.values(), bool, count=num_robots)
            _copy(group.get("reward"), rewards[:, None])
            _copy(group.get("terminated"), terminated[:, None])
            _copy(group.get("truncated"), truncated[:, None])
            _copy(group.get("done"), (terminated | truncated)[:, None])
        info = group.get("info", None)
        if info is not None:
            # The env shares one info dict between all its agents.
            for key, value in raw.infos[raw.agent_selection].items():
                info.get(key).fill_(value)
        if self.return_state:
            out.set("state", self.observation_spec["state"].encode(raw.state()))
        return out


def _copy_features(target: torch.Tensor | TensorDictBase, features: Features) -> None:
    if isinstance(features, np.ndarray):
        _copy(target, features)
        return
    for key, values in features.items():
        _copy(target.get(key), values)


def _copy(target: torch.Tensor, values: np.ndarray) -> None:
    """``target[...] = values`` (a NumPy array, possibly a read-only broadcast view)."""
    if target.device.type == "cpu":
        np.copyto(target.numpy(), values, casting="same_kind")
    else:
        target.copy_(torch.from_numpy(np.ascontiguousarray(values)))
