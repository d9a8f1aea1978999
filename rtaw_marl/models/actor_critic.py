"""TorchRL actor and critic modules around the RTAW networks, on explicit keys.

Each network names its inputs in ``in_keys`` (observation entries, the action mask
last); the caller passes the tensordict key of each, which may be nested.
"""

from __future__ import annotations

from rtaw_marl.errors import missing_extra

# Without the training extra: one error that names it (errors.missing_extra), no traceback
# of a bare ModuleNotFoundError.
try:
    import torch
    from tensordict import TensorDictBase
    from tensordict.nn import TensorDictModule
    from torchrl.modules import MaskedCategorical, ProbabilisticActor, ValueOperator
except ModuleNotFoundError as exc:
    raise missing_extra(exc, __name__, "train") from None

from rtaw_marl.models.checkpoint import Actor, Critic

__all__ = ["greedy_action", "make_actor", "make_critic"]


def make_actor(net: Actor, keys: tuple | None = None) -> ProbabilisticActor:
    """A stochastic actor: logits -> ``MaskedCategorical`` over the queue slots.

    Args:
        net: The policy network.
        keys: The tensordict key of each of ``net.in_keys`` (default: those names);
            nested keys are allowed (the PettingZoo interop route uses them).

    Returns:
        A module writing ``"logits"``, ``"action"`` and ``"action_log_prob"``.
    """
    keys = tuple(net.in_keys) if keys is None else tuple(keys)
    # Outputs go next to the action mask: ("agents", ...) on the interop route.
    prefix = keys[-1][:-1] if isinstance(keys[-1], tuple) else ()
    logits_key = (*prefix, "logits") if prefix else "logits"
    action_key = (*prefix, "action") if prefix else "action"
    module = TensorDictModule(net, in_keys=list(keys), out_keys=[logits_key])
    return ProbabilisticActor(
        module,
        in_keys={"logits": logits_key, "mask": keys[-1]},
        out_keys=[action_key],
        distribution_class=MaskedCategorical,
        return_log_prob=True,
        log_prob_key=(*prefix, "action_log_prob") if prefix else "action_log_prob",
    )


def make_critic(net: Critic, keys: tuple | None = None) -> ValueOperator:
    """A value module writing ``"state_value"`` (next to the observation keys)."""
    keys = tuple(net.in_keys) if keys is None else tuple(keys)
    # Outputs go next to the action mask: ("agents", ...) on the interop route.
    prefix = keys[-1][:-1] if isinstance(keys[-1], tuple) else ()
    out = (*prefix, "state_value") if prefix else "state_value"
    return ValueOperator(net, in_keys=list(keys), out_keys=[out])


def greedy_action(net: Actor, td: TensorDictBase) -> torch.Tensor:
    """The non-empty slot with the largest logit, ``int64 [*]``, from a tensordict holding
    ``net.in_keys`` at the top level."""
    logits = net(*(td[key] for key in net.in_keys))
    return logits.masked_fill(~td["action_mask"], -torch.inf).argmax(-1)
