"""The check of an exported actor: the Python policy's decisions, replayed.

:func:`record_decisions` plays one ``warehouse_v1`` episode with the Python policy
(:meth:`~rtaw_marl.policies.network.NetworkPolicy.act` on the env's observations) and
keeps the network inputs of every decision; :func:`check_exported` runs an exported
model on them, all decisions as one batch, and compares its logits with the eager
network's and its argmax with the policy's choices (:class:`CheckReport`).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rtaw_marl.errors import missing_extra

# Without the training extra: one error that names it (errors.missing_extra), no traceback
# of a bare ModuleNotFoundError.
try:
    import torch
except ModuleNotFoundError as exc:
    raise missing_extra(exc, __name__, "train") from None

from rtaw_marl.decision.observations import read_features
from rtaw_marl.models.checkpoint import Actor
from rtaw_marl.policies.network import NetworkPolicy

__all__ = ["CheckReport", "Runner", "check_exported", "record_decisions"]

#: An exported model as a function: ``{input name: array [B, ...]} -> logits [B, N]``.
Runner = Callable[[Mapping[str, np.ndarray]], np.ndarray]


@dataclass(frozen=True)
class CheckReport:
    """What the check of an exported model found.

    Attributes:
        decisions: Decisions recorded and compared.
        shapes: Shape of each recorded input (the export traced 2 decisions, 3 slots, 4
            robots, so these sizes test its dynamic dimensions).
        max_abs_diff: Largest ``|exported - eager|`` over the unmasked logits.
        atol: Absolute tolerance: every unmasked logit must be within ``atol + rtol *
            |eager|`` (logits reach the hundreds, where float32 rounding alone is 1e-5).
        rtol: Relative tolerance.
        within_tolerance: Every unmasked logit was within it.
        choices_equal: Decisions where the exported argmax is the policy's action.
        masked_equal: Whether exactly the masked slots are ``-inf``.
        env: The env's arguments and seed of the recorded episode.
    """

    decisions: int
    shapes: dict[str, list[int]]
    max_abs_diff: float
    atol: float
    rtol: float
    within_tolerance: bool
    choices_equal: int
    masked_equal: bool
    env: dict[str, Any] = field(default_factory=dict)

    @property
    def ok(self) -> bool:
        """Every choice equal, the masks equal and the logits within ``atol``."""
        return self.choices_equal == self.decisions and self.masked_equal and self.within_tolerance

    def summary(self) -> str:
        """One line: decisions, max difference, choices."""
        return (
            f"{self.decisions} decisions {self.shapes}: max |logit diff| "
            f"{self.max_abs_diff:.2e} (atol {self.atol:g} + rtol {self.rtol:g} x |logit|: "
            f"{'within' if self.within_tolerance else 'NOT within'}), same choice at "
            f"{self.choices_equal}/{self.decisions}"
        )


def record_decisions(
    policy: NetworkPolicy, env_args: Mapping[str, Any], seed: int
) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """Play one ``warehouse_v1`` episode with ``policy.act`` and record its inputs.

    Args:
        policy: The Python policy (no ``candidates``: it scores every slot).
        env_args: Arguments of ``warehouse_v1.env`` (``observation`` is set to ``full``).
        seed: The episode's seed.

    Returns:
        ``({key: [D, ...]} the network inputs of the ``D`` decisions, stacked, the mask
        as bool; actions int64 [D]`` the slots the policy chose).
    """
    from rtaw_marl import warehouse_v1

    keys = policy.net.in_keys
    env = warehouse_v1.env(**{**env_args, "observation": "full"})
    env.reset(seed=seed)
    rows: dict[str, list[np.ndarray]] = {key: [] for key in keys}
    actions: list[int] = []
    for _agent in env.agent_iter():
        obs, _, terminated, truncated, _ = env.last()
        if terminated or truncated:
            env.step(None)
            continue
        action = policy.act(obs)
        features = read_features(obs, keys[:-1], policy.name)
        for key in keys[:-1]:
            rows[key].append(np.array(features[key], dtype=np.float32))
        rows["action_mask"].append(np.asarray(obs["action_mask"]).astype(bool))
        actions.append(action)
        env.step(action)
    env.close()
    return {key: np.stack(value) for key, value in rows.items()}, np.asarray(actions)


def check_exported(
    run: Runner,
    actor: Actor,
    inputs: Mapping[str, np.ndarray],
    actions: np.ndarray,
    atol: float,
    rtol: float,
    env: Mapping[str, Any] | None = None,
) -> CheckReport:
    """Compare an exported model with the eager ``actor`` on recorded decisions.

    Args:
        run: The exported model (:func:`load_exported`).
        actor: The Python network.
        inputs: The recorded inputs ``[D, ...]`` (:func:`record_decisions`).
        actions: The Python policy's choices ``[D]``.
        atol: Absolute tolerance on the logits.
        rtol: Relative tolerance on the logits (of the eager logit's magnitude).
        env: The recorded episode's env arguments and seed, for the report.

    Returns:
        The report; the caller decides what a failure means.
    """
    mask = inputs["action_mask"]
    with torch.no_grad():
        eager = actor(*(torch.from_numpy(inputs[k]) for k in actor.in_keys)).numpy()
    exported = np.asarray(run(inputs))
    masked_equal = exported.shape == mask.shape and bool((np.isneginf(exported) == ~mask).all())
    eager = np.where(mask, eager, 0.0)
    diff = np.abs(np.where(mask, exported, 0.0) - eager)
    choices = np.argmax(np.where(mask, exported, -np.inf), axis=-1) if masked_equal else -1
    return CheckReport(
        decisions=len(actions),
        shapes={k: list(v.shape) for k, v in inputs.items()},
        max_abs_diff=float(diff.max(initial=0.0)) if masked_equal else float("inf"),
        atol=atol,
        rtol=rtol,
        within_tolerance=masked_equal and bool((diff <= atol + rtol * np.abs(eager)).all()),
        choices_equal=int(np.sum(choices == actions)),
        masked_equal=masked_equal,
        env=dict(env or {}),
    )
