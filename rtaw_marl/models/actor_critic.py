"""TorchRL actor and critic modules around the RTAW networks, on explicit keys."""

from __future__ import annotations

from tensordict.nn import TensorDictModule
from torchrl.modules import MaskedCategorical, ProbabilisticActor, ValueOperator

from rtaw_marl.envs.features import OBSERVATION_KEYS
from rtaw_marl.models.rtaw import RTAWActor, RTAWCritic

__all__ = ["OBSERVATION_KEYS", "make_actor", "make_critic"]


def make_actor(net: RTAWActor, keys: tuple = OBSERVATION_KEYS) -> ProbabilisticActor:
    """A stochastic actor: logits -> ``MaskedCategorical`` over the queue slots.

    Args:
        net: The policy network.
        keys: The observation keys in the order ``(robots, tasks, agent, action_mask)``;
            nested keys are allowed (the PettingZoo interop route uses them).

    Returns:
        A module writing ``"logits"``, ``"action"`` and ``"action_log_prob"``.
    """
    # Outputs go next to the action mask: ("agents", ...) on the interop route.
    prefix = keys[3][:-1] if isinstance(keys[3], tuple) else ()
    logits_key = (*prefix, "logits") if prefix else "logits"
    action_key = (*prefix, "action") if prefix else "action"
    module = TensorDictModule(net, in_keys=list(keys), out_keys=[logits_key])
    return ProbabilisticActor(
        module,
        in_keys={"logits": logits_key, "mask": keys[3]},
        out_keys=[action_key],
        distribution_class=MaskedCategorical,
        return_log_prob=True,
        log_prob_key=(*prefix, "action_log_prob") if prefix else "action_log_prob",
    )


def make_critic(net: RTAWCritic, keys: tuple = OBSERVATION_KEYS) -> ValueOperator:
    """A value module writing ``"state_value"`` (next to the observation keys)."""
    # Outputs go next to the action mask: ("agents", ...) on the interop route.
    prefix = keys[3][:-1] if isinstance(keys[3], tuple) else ()
    out = (*prefix, "state_value") if prefix else "state_value"
    return ValueOperator(net, in_keys=list(keys), out_keys=[out])
