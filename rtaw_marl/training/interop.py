"""The interop route: training through TorchRL's ``PettingZooWrapper`` on the AEC env.

This is how other MARL libraries plug the env in. All robots form one group
(``MarlGroupMapType.ALL_IN_ONE_GROUP``). The env's observation ``{"observation":
features, "action_mask": mask}`` arrives as ``("agents", "observation", "observation",
name)`` per feature (the wrapper nests the env's ``"observation"`` entry under its own)
and ``("agents", "action_mask")``; ``("agents", "mask")`` marks the acting robot of each
step, the loss counts only that row (``loss_mask_key``), and the episode metrics arrive
as ``("agents", "info", name)``.

The env is built with ``observation="full"`` and ``obs_format="dict"``: ``model=rtaw``
reads the robot table ``robots`` in its actor and critic, and ``model=rtaw_plus`` in its
critic, and the full observation carries it per agent. (The compact observation has no
robot table; the wrapper's ``return_state`` would put ``state()`` at the root, outside
the ``"agents"`` group the networks read.) The wrapper is
:class:`~rtaw_marl.envs.torchrl_wrapper.WarehouseWrapper`, the ``PettingZooWrapper``
subclass that fills every robot's row at once (bit-identical to the stock wrapper). The
full observation still costs ``O(M^2)`` per step (``[M, M, 3]`` robot tables): this
route is for small ``M``; the batched native env is the fast route.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from rtaw_marl.errors import missing_extra

# Without the training extra: one error that names it (errors.missing_extra), no traceback
# of a bare ModuleNotFoundError.
try:
    import torch
    from tensordict import TensorDictBase
    from tensordict.utils import NestedKey
except ModuleNotFoundError as exc:
    raise missing_extra(exc, __name__, "train") from None

from rtaw_marl.envs.pettingzoo import env as warehouse_env
from rtaw_marl.envs.torchrl_wrapper import WarehouseWrapper
from rtaw_marl.sim.builder import SimSpec

__all__ = [
    "BATCHED_KEYS",
    "INTEROP_KEYS",
    "TrainKeys",
    "acting_reward",
    "make_interop_env",
    "standardize_acting_advantage",
]


@dataclass(frozen=True)
class TrainKeys:
    """Every tensordict key the trainer reads or writes, spelled out.

    ``observation_root`` is where observation entries live (``()``: at the top level) and
    ``action_mask`` the mask's own key; :meth:`observation` spells a network's inputs.
    """

    observation_root: tuple[str, ...]
    action_mask: NestedKey
    action: NestedKey
    log_prob: NestedKey
    value: NestedKey
    reward: NestedKey
    done: NestedKey
    terminated: NestedKey
    advantage: NestedKey
    value_target: NestedKey
    loss_mask: NestedKey | None

    def observation(self, names: tuple[str, ...]) -> tuple[NestedKey, ...]:
        """The keys of observation entries ``names`` (a network's ``in_keys``)."""
        return tuple(
            self.action_mask
            if name == "action_mask"
            else ((*self.observation_root, name) if self.observation_root else name)
            for name in names
        )


BATCHED_KEYS = TrainKeys(
    observation_root=(),
    action_mask="action_mask",
    action="action",
    log_prob="action_log_prob",
    value="state_value",
    reward="reward",
    done="done",
    terminated="terminated",
    advantage="advantage",
    value_target="value_target",
    loss_mask=None,
)

INTEROP_KEYS = TrainKeys(
    observation_root=("agents", "observation", "observation"),
    action_mask=("agents", "action_mask"),
    action=("agents", "action"),
    log_prob=("agents", "action_log_prob"),
    value=("agents", "state_value"),
    reward=("agents", "reward"),
    done=("agents", "done"),
    terminated=("agents", "terminated"),
    advantage=("agents", "advantage"),
    value_target=("agents", "value_target"),
    loss_mask=("agents", "mask"),
)


def make_interop_env(spec: SimSpec, seed: int) -> WarehouseWrapper:
    """The AEC warehouse env in a ``PettingZooWrapper``, all robots in one group.

    Args:
        spec: The simulator spec.
        seed: Seed of the first reset.
    """
    sim_keys = {f.name: getattr(spec.sim, f.name) for f in dataclasses.fields(spec.sim)}
    aec = warehouse_env(
        layout=spec.layout, navigator=spec.navigator, tasks=spec.tasks,
        observation="full", obs_format="dict", **sim_keys,
    )  # fmt: skip
    return WarehouseWrapper(aec, seed=seed, training=True)


def acting_reward(data: TensorDictBase, keys: TrainKeys) -> float:
    """Mean reward per decision of a collected batch (raw units: minus seconds)."""
    reward = data["next", keys.reward]
    if keys.loss_mask is None:
        return reward.mean().item()
    mask = data[keys.loss_mask]
    return reward.squeeze(-1)[mask].mean().item()


def standardize_acting_advantage(data: TensorDictBase, keys: TrainKeys) -> None:
    """Standardise the advantages of the acting rows of a batch, in place.

    On the interop route every step has a row per robot and only the acting robot's
    counts (``keys.loss_mask``). The loss's own normalisation would take the mean and
    spread over every row, the meaningless non-acting ones included, so this route
    standardises over the acting rows here and turns the loss's off. Non-acting rows
    are set to 0 (the loss masks them out anyway).
    """
    advantage = data[keys.advantage]
    mask = data[keys.loss_mask].unsqueeze(-1).expand_as(advantage)
    acting = advantage[mask]
    scale = acting.std(unbiased=False).clamp_min(1e-4) if acting.numel() > 1 else 1.0
    data[keys.advantage] = torch.where(mask, (advantage - acting.mean()) / scale, 0.0)
