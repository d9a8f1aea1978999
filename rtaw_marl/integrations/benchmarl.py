"""The warehouse env as a BenchMARL task: ``rtaw/warehouse`` (docs/benchmarl.md).

BenchMARL's own PettingZoo tasks (``benchmarl/environments/pettingzoo/common.py``) build
``PettingZooEnv(parallel=True)`` over the library's MPE and SISL envs. This task follows
the same :class:`~benchmarl.environments.TaskClass` pattern, with a typed schema
(:class:`TaskConfig`, every field ``MISSING``) and its YAML (``conf/warehouse.yaml``
beside this file), for the AEC warehouse env: ``WarehouseWrapper(warehouse_v1.env(...))``
(TorchRL's ``PettingZooWrapper`` with ``use_mask=True``, every robot's row filled at
once), all robots in one group ``"agents"``, discrete actions only.

What BenchMARL gets from the env:

* observation ``("agents", "observation", "observation")`` ``[M, F]``: the env's flat
  features (``obs_format="flat"``: BenchMARL's MLP concatenates its inputs and needs the
  same leading shape for all of them, which the dict features do not have);
  ``observation="compact"`` by default, so ``F = 46N + 3`` does not grow with ``M``;
* action mask ``("agents", "action_mask")`` ``[M, N]`` (BenchMARL's PPO/MAPPO then use a
  ``MaskedCategorical``);
* state ``"state"`` ``[3M + 7N]`` from ``state()`` (``return_state=True``): the MAPPO
  critic reads it;
* info ``("agents", "info")``: the episode metrics (``ttd``, ``makespan``, ...), non-zero
  at the last step of an episode;
* ``max_steps`` = ``num_tasks`` (one decision per step), ``has_render`` False (the env
  renders text, not the ``rgb_array`` pixels BenchMARL's videos need).

What BenchMARL does not know about the AEC route, and what this task does about it.
TorchRL's wrapper gives every robot a row at every step, marks the robot that acts in
``("agents", "mask")`` and gives the other rows an all-True action mask; their actions
are ignored. BenchMARL's losses read no ``mask`` key: every row would enter the policy
loss, nine of ten of them (at ``M = 10``) with an action that changed nothing. Two env
transforms (:class:`ActingRobotRows`, on by default, each a YAML switch) make BenchMARL's
unchanged algorithms learn the env's MDP:

* ``acting_only_loss``: the action mask of a row that does not act becomes one-hot (slot
  0). A masked categorical with one valid action has log-probability 0 and entropy 0
  whatever the logits, so those rows add nothing to the PPO objective or its entropy
  bonus: the policy loss counts the acting robot only (as ``loss_mask_key`` would).
* ``team_reward``: the env rewards the acting robot only; every robot gets the sum (the
  acting robot's reward) instead, the paper's team objective (total travel delay). With
  MAPPO's shared critic on the global state, all robots then share one value target.

Rewards are multiplied by ``reward_scale`` (``null``: ``1 / L``, the layout scale, as
``rtaw-train`` does), so that values stay near 1.

BenchMARL 1.5.2 (the newest release) declares ``torchrl<0.12`` and imports
``torchrl.collectors.SyncDataCollector``, which torchrl 0.14 removed in favour of
``Collector``. Importing this module first installs that name as a thin alias of
``Collector`` (only when it is missing); nothing else in BenchMARL needs changing for
torchrl 0.14.1 (MAPPO's ``ClipPPOLoss(entropy_coeff=...)`` already uses 0.14's names).
Install with ``pip install --no-deps benchmarl==1.5.2`` (docs/benchmarl.md).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import MISSING, dataclass
from pathlib import Path
from typing import Any

from rtaw_marl.errors import missing_extra

# Without the training extra: one error that names it (errors.missing_extra), no traceback
# of a bare ModuleNotFoundError.
try:
    import torch
    import torchrl.collectors
    from omegaconf import OmegaConf
    from tensordict import TensorDictBase
    from torchrl.data import Composite
    from torchrl.envs import EnvBase, Transform
except ModuleNotFoundError as exc:
    raise missing_extra(exc, __name__, "train") from None

from rtaw_marl.envs.pettingzoo import env as warehouse_env
from rtaw_marl.envs.torchrl_wrapper import WarehouseWrapper


def _install_collector_alias() -> None:
    """``torchrl.collectors.SyncDataCollector`` as ``Collector``, for BenchMARL 1.5.2."""
    if hasattr(torchrl.collectors, "SyncDataCollector"):
        return

    def SyncDataCollector(*args: Any, **kwargs: Any) -> torchrl.collectors.Collector:
        kwargs.setdefault("auto_register_policy_transforms", False)
        return torchrl.collectors.Collector(*args, **kwargs)

    torchrl.collectors.SyncDataCollector = SyncDataCollector


_install_collector_alias()

from benchmarl.environments import Task, TaskClass  # noqa: E402

__all__ = [
    "CONFIG_PATH",
    "ActingRobotRows",
    "TaskConfig",
    "WarehouseClass",
    "WarehouseTask",
    "load_task_config",
]

#: The task's YAML (the values of :class:`TaskConfig`).
CONFIG_PATH = Path(__file__).resolve().parent / "conf" / "warehouse.yaml"


@dataclass
class TaskConfig:
    """Schema of ``rtaw/warehouse`` (values and comments: ``conf/warehouse.yaml``)."""

    layout: Any = MISSING
    navigator: Any = MISSING
    tasks: Any = MISSING
    num_robots: int = MISSING
    num_tasks: int = MISSING
    queue_len: int = MISSING
    episode_mode: str = MISSING
    observation: str = MISSING
    sim: dict[str, Any] = MISSING
    acting_only_loss: bool = MISSING
    team_reward: bool = MISSING
    reward_scale: float | None = MISSING


def load_task_config(path: str | Path | None = None, **overrides: Any) -> dict[str, Any]:
    """The task config: a YAML (default: the packaged one) checked against :class:`TaskConfig`.

    Args:
        path: A task YAML; ``None``: ``conf/warehouse.yaml``.
        **overrides: Keys of :class:`TaskConfig` to replace.

    Raises:
        omegaconf.errors.ConfigKeyError: An unknown key.
        omegaconf.errors.ValidationError: A value of the wrong type.
        omegaconf.errors.MissingMandatoryValue: A key left unset.
    """
    values = OmegaConf.load(CONFIG_PATH if path is None else path)
    values.pop("defaults", None)
    merged = OmegaConf.merge(OmegaConf.structured(TaskConfig), values, overrides)
    return OmegaConf.to_container(merged, resolve=True, throw_on_missing=True)


class ActingRobotRows(Transform):
    """Team reward and one-hot action masks on the rows of robots that do not act.

    See the module docstring. Keys: ``(group, "reward")`` (``[..., M, 1]``), ``(group,
    "mask")`` (``[..., M]``, the acting robot) and ``(group, "action_mask")`` (``[..., M,
    N]``); specs are unchanged.

    Args:
        group: The agent group.
        reward_scale: Rewards are multiplied by this.
        team_reward: Every robot gets the step's summed reward.
        acting_only_loss: One-hot masks (slot 0) on the rows that do not act.
    """

    def __init__(
        self, group: str, reward_scale: float, team_reward: bool, acting_only_loss: bool
    ) -> None:
        super().__init__(in_keys=[], out_keys=[])
        self.group = group
        self.reward_scale = float(reward_scale)
        self.team_reward = team_reward
        self.acting_only_loss = acting_only_loss

    def _call(self, next_tensordict: TensorDictBase) -> TensorDictBase:
        key = (self.group, "reward")
        reward = next_tensordict.get(key, None)
        if reward is not None:
            if self.team_reward:
                reward = reward.sum(-2, keepdim=True).expand_as(reward)
            next_tensordict.set(key, reward * self.reward_scale)
        if self.acting_only_loss:
            acting = next_tensordict.get((self.group, "mask")).unsqueeze(-1)
            action_mask = next_tensordict.get((self.group, "action_mask"))
            one_hot = torch.zeros_like(action_mask)
            one_hot[..., 0] = True
            next_tensordict.set(
                (self.group, "action_mask"), torch.where(acting, action_mask, one_hot)
            )
        return next_tensordict

    def _reset(
        self, tensordict: TensorDictBase, tensordict_reset: TensorDictBase
    ) -> TensorDictBase:
        return self._call(tensordict_reset)


def _only(spec: Composite, groups: list[str], entry: str) -> Composite:
    """``spec`` with each group holding only ``entry``, and no ``state``."""
    spec = spec.clone()
    for group in groups:
        for key in list(spec[group].keys()):
            if key != entry:
                del spec[group][key]
    if "state" in spec.keys():  # noqa: SIM118 (a Composite spec is not a dict)
        del spec["state"]
    return spec


class WarehouseClass(TaskClass):
    """How BenchMARL builds ``rtaw/warehouse`` (the module docstring lists what it gets)."""

    def get_env_fun(
        self,
        num_envs: int,
        continuous_actions: bool,
        seed: int | None,
        device: torch.device | str | int,
    ) -> Callable[[], EnvBase]:
        """A constructor of one wrapped env (not vectorised: BenchMARL batches it with
        ``SerialEnv``/``ParallelEnv`` of ``num_envs``; ``continuous_actions`` is ignored)."""
        config = dict(self.config)

        def make() -> EnvBase:
            aec = warehouse_env(
                layout=config["layout"], navigator=config["navigator"], tasks=config["tasks"],
                observation=config["observation"], obs_format="flat",
                num_robots=config["num_robots"], num_tasks=config["num_tasks"],
                queue_len=config["queue_len"], episode_mode=config["episode_mode"],
                **config["sim"],
            )  # fmt: skip
            return WarehouseWrapper(aec, return_state=True, seed=seed, device=device, training=True)

        return make

    def supports_continuous_actions(self) -> bool:
        return False

    def supports_discrete_actions(self) -> bool:
        return True

    def has_render(self, env: EnvBase) -> bool:
        return False

    def max_steps(self, env: EnvBase) -> int:
        return int(self.config["num_tasks"])

    def group_map(self, env: EnvBase) -> dict[str, list[str]]:
        return env.group_map

    def observation_spec(self, env: EnvBase) -> Composite:
        return _only(env.observation_spec, list(self.group_map(env)), "observation")

    def action_mask_spec(self, env: EnvBase) -> Composite:
        return _only(env.observation_spec, list(self.group_map(env)), "action_mask")

    def info_spec(self, env: EnvBase) -> Composite:
        return _only(env.observation_spec, list(self.group_map(env)), "info")

    def state_spec(self, env: EnvBase) -> Composite:
        return Composite({"state": env.observation_spec["state"].clone()})

    def action_spec(self, env: EnvBase) -> Composite:
        return env.full_action_spec

    def get_env_transforms(self, env: EnvBase) -> list[Transform]:
        scale = self.config["reward_scale"]
        if scale is None:
            # The layout scale L of the wrapped AEC env (PettingZooWrapper keeps it in _env).
            scale = 1.0 / env._env.unwrapped.scale
        return [
            ActingRobotRows(
                group=next(iter(self.group_map(env))),
                reward_scale=scale,
                team_reward=self.config["team_reward"],
                acting_only_loss=self.config["acting_only_loss"],
            )
        ]

    @staticmethod
    def log_info(batch: TensorDictBase) -> dict[str, float]:
        """The mean metrics of the episodes that ended in ``batch`` (nothing if none did)."""
        done = batch.get(("next", "done")).squeeze(-1)
        if not done.any():
            return {}
        info = batch.get(("next", "agents", "info"))[done][..., 0]
        return {
            f"collection/episode/{key}": value.float().mean().item() for key, value in info.items()
        }

    @staticmethod
    def env_name() -> str:
        return "rtaw"


class WarehouseTask(Task):
    """The tasks of environment ``rtaw``: ``WAREHOUSE`` (``rtaw/warehouse``).

    ``WarehouseTask.WAREHOUSE.get_task()`` loads the packaged YAML;
    ``get_from_yaml(path)`` another one; ``get_task(config)`` takes a full config
    (:func:`load_task_config` builds one with overrides).
    """

    WAREHOUSE = None

    @staticmethod
    def associated_class() -> type[WarehouseClass]:
        return WarehouseClass

    def get_from_yaml(self, path: str | None = None) -> WarehouseClass:
        """The task with the config of ``path`` (default: the packaged YAML), type-checked."""
        return self.get_task(config=load_task_config(path))
