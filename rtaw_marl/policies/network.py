"""Trained RTAW networks as greedy policies, loaded from checkpoints or the shipped zoo.

A :class:`NetworkPolicy` acts on the bare simulator (``act_sim``, the evaluation's fast
path) and on ``warehouse_v1`` observations (``act``); both feed the network the
very arrays of :func:`~rtaw_marl.decision.features.decision_features`, so they choose the
same slot bit for bit. The paper's network (``model=rtaw``) reads ``robots``, ``tasks``
and ``agent``: it needs ``observation="full"``; RTAW+ (``model=rtaw_plus``) reads
``relations`` and ``rivals``: ``"full"`` or ``"compact"``; dict or flat features alike.

With ``candidates=K`` a policy scores only the ``K`` queued tasks whose origins are
nearest the free robot (:func:`~rtaw_marl.decision.features.candidate_slots`) when the queue
holds more: on the fast path only their features are computed, so a decision costs
``O(K)`` network work and ``O(N)`` cheap distance lookups, not ``O(N)`` network work.
"""

from __future__ import annotations

import difflib
import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from rtaw_marl.errors import ConfigError, missing_extra

# Without the training extra: one error that names it (errors.missing_extra), no traceback
# of a bare ModuleNotFoundError.
try:
    import torch
except ModuleNotFoundError as exc:
    raise missing_extra(exc, __name__, "train") from None

from rtaw_marl.decision.features import candidate_slots, sim_observation
from rtaw_marl.decision.observations import read_features
from rtaw_marl.models.checkpoint import Actor, load_checkpoint, load_networks
from rtaw_marl.models.rtaw_plus import RTAWPlusActor
from rtaw_marl.policies.labels import checkpoint_labels
from rtaw_marl.policies.pretrained.registry import PRETRAINED, pretrained_path
from rtaw_marl.sim.core import WarehouseSim

__all__ = ["PER_TASK_KEYS", "NetworkPolicy", "checkpoint_path", "load_policy"]

#: Observation entries with one row per queue slot (what ``candidates`` selects from).
PER_TASK_KEYS = frozenset({"tasks", "relations", "rivals"})


def load_policy(
    source: str | Path,
    *,
    name: str | None = None,
    torch_threads: int | None = 1,
    candidates: int | None = None,
) -> NetworkPolicy:
    """A greedy policy from a checkpoint file or a shipped pretrained name.

    The policy runs on any ``M``, ``N``, layout or navigator; see :class:`NetworkPolicy`.

    Args:
        source: A checkpoint path, or the name of a shipped policy
            (``rtaw_marl.policies.pretrained.registry.PRETRAINED``, e.g.
            ``"shelves_astar_m10_plus"``).
        name: Label in result tables; by default a shipped policy's name, or the end of
            the checkpoint's path (:func:`~rtaw_marl.policies.labels.checkpoint_labels`).
        torch_threads: ``torch.set_num_threads`` for the process (one decision is a small
            network: with every thread an episode takes about ten times longer);
            ``None`` leaves torch as it is.
        candidates: Score only the ``K`` tasks nearest the free robot when the queue
            holds more (:class:`NetworkPolicy`); ``None``: every queued task.

    Returns:
        The policy: ``act(observation) -> int`` and ``act_sim(sim) -> int``.

    Raises:
        ConfigError: ``source`` is neither a file nor a shipped name (the message
            suggests names), or the checkpoint is unreadable, unsafe, for another
            feature layout, or its weights do not fit its model.
    """
    path = checkpoint_path(source)
    if torch_threads is not None:
        torch.set_num_threads(int(torch_threads))
    actor, _ = load_networks(load_checkpoint(path), path)
    label = name or checkpoint_labels([str(source)])[0]
    return NetworkPolicy(actor, name=label, candidates=candidates)


def checkpoint_path(source: str | Path) -> Path:
    """The checkpoint file of a path or shipped name.

    Raises:
        ConfigError: Neither a path that exists nor a shipped name (close names listed).
    """
    path = Path(source)
    # Anything at the path (a folder, a FIFO, a broken symlink) is the checkpoint meant:
    # load_checkpoint says what is wrong with it, rather than "not a shipped name".
    if isinstance(source, Path) or os.path.lexists(path):
        return path
    if source in PRETRAINED:
        return pretrained_path(source)
    close = difflib.get_close_matches(str(source), list(PRETRAINED), n=3)
    hint = f"; did you mean {', '.join(close)}?" if close else ""
    raise ConfigError(
        f"{source!r} is neither a checkpoint file nor a shipped pretrained policy{hint} "
        f"Shipped: {', '.join(sorted(PRETRAINED))}"
    )


class NetworkPolicy:
    """Greedy (argmax) decisions of a trained policy network.

    Args:
        net: A trained actor (``in_keys`` name its observation entries, the action mask
            last; ``net(*inputs)`` gives logits ``[*, N]``).
        name: Label used in result tables.
        candidates: ``K``: when the queue holds more than ``K`` slots, score only the
            ``K`` tasks whose origins are nearest the free robot (ties: the lowest
            slot); ``None``: every queued task. Both paths retrieve the same ``K``
            (from the float32 distance the observation holds).

    Raises:
        ConfigError: ``candidates`` is not an integer >= 1.
    """

    def __init__(self, net: Actor, name: str = "rtaw", candidates: int | None = None) -> None:
        if candidates is not None and (
            isinstance(candidates, bool) or not isinstance(candidates, int) or candidates < 1
        ):
            raise ConfigError(f"candidates must be an integer >= 1 or None, got {candidates!r}")
        self.net = net.eval()
        self.name = name
        self.candidates = candidates
        self._features = tuple(key for key in net.in_keys if key != "action_mask")
        # RTAW+'s inputs have no fleet axis, so one frozen TorchScript trace serves every
        # decision: a third of the eager call's Python overhead, the same logits bit for
        # bit (tests/policies). Built at the first decision, from the weights then.
        self._traceable = isinstance(net, RTAWPlusActor)
        self._fast: torch.jit.ScriptModule | None = None

    @property
    def feature_keys(self) -> tuple[str, ...]:
        """The observation entries the network reads (its ``in_keys`` but the mask)."""
        return self._features

    def reset(self, seed: int | None = None) -> None:
        """Nothing to seed: greedy decisions are deterministic."""

    @torch.no_grad()
    def act_sim(self, sim: WarehouseSim) -> int:
        """The slot with the largest logit among the non-empty ones (fast path)."""
        slots = None
        if self.candidates is not None and sim.queue_len > self.candidates:
            # The key the observation holds (distance / L in float32), so act() on the
            # env's observation retrieves exactly these slots.
            key = (sim.robot_distances() / sim.layout.scale).astype(np.float32)
            slots = candidate_slots(key, sim.queue_mask, self.candidates)
        obs = sim_observation(sim, self._features, slots)
        best = self._argmax([obs[key] for key in self._features], obs["action_mask"])
        return best if slots is None else int(slots[best])

    @torch.no_grad()
    def act(self, observation: Mapping[str, Any]) -> int:
        """The slot with the largest logit, from a ``warehouse_v1`` observation.

        Args:
            observation: ``{"observation": features, "action_mask": int8 [N]}`` (dict or
                flat features; ``features [...]`` of one agent).

        Raises:
            ConfigError: The observation lacks a feature the network reads (the paper's
                network needs ``observation="full"``).
        """
        features = read_features(observation, self._features, self.name)
        mask = np.asarray(observation["action_mask"]).astype(bool)
        if self.candidates is None or len(mask) <= self.candidates:
            return self._argmax([features[key] for key in self._features], mask)
        # relations[:, 0] and tasks[:, 4] both hold the free robot's distance / L.
        key = features["relations"][:, 0] if "relations" in features else features["tasks"][:, 4]
        slots = candidate_slots(key, mask, self.candidates)
        inputs = [x[slots] if k in PER_TASK_KEYS else x for k, x in features.items()]
        return int(slots[self._argmax(inputs, mask[slots])])

    @torch.no_grad()
    def act_batch(self, observation: Mapping[str, Any]) -> np.ndarray:
        """The greedy slots of ``B`` decisions at once, with one network call.

        Row ``b`` is :meth:`act` of row ``b``'s observation (the same candidates and the
        same slot, tested), so ``B`` environments' decisions, or every row of
        ``observe_all()``, cost one forward pass instead of ``B``.

        Args:
            observation: ``{"observation": features [B, ...], "action_mask": [B, N]}``
                (dict or flat features, stacked over the decisions).

        Returns:
            ``int64 [B]``: the chosen slots; ``-1`` for a row whose mask is all zeros
            (``observe_all()``'s rows of robots that are not acting).

        Raises:
            ConfigError: The mask is not ``[B, N]``, an entry does not hold the same
                ``B`` decisions, or the observation lacks a feature the network reads.
        """
        mask = np.asarray(observation["action_mask"]).astype(bool)
        if mask.ndim != 2:
            raise ConfigError(f"act_batch needs action_mask [B, N], got shape {mask.shape}")
        features = read_features(observation, self._features, self.name)
        inputs = [features[key] for key in self._features]
        for key, x in zip(self._features, inputs, strict=True):
            if x.shape[:1] != mask.shape[:1]:
                raise ConfigError(
                    f"act_batch: {key} has shape {x.shape}, but action_mask {mask.shape}: "
                    "every entry needs the same B decisions first"
                )
        slots = None
        if self.candidates is not None and mask.shape[1] > self.candidates:
            # Per row, candidate_slots' choice: the K nearest, ties to the lower slot.
            key = features["relations"][..., 0] if "relations" in features else (
                features["tasks"][..., 4])  # fmt: skip
            nearest = np.argsort(np.where(mask, key, np.inf), axis=1, kind="stable")
            slots = np.sort(nearest[:, : self.candidates], axis=1)  # [B, K]
            inputs = [
                _take_slots(x, slots) if k in PER_TASK_KEYS else x
                for k, x in zip(self._features, inputs, strict=True)
            ]
            mask = np.take_along_axis(mask, slots, axis=1)
        tensors = [torch.from_numpy(np.require(x, np.float32, "CW")) for x in inputs]
        m = torch.from_numpy(np.require(mask, bool, "CW"))
        best = torch.where(m, self.net(*tensors, m), -torch.inf).argmax(-1).numpy()
        if slots is not None:
            best = np.take_along_axis(slots, best[:, None], axis=1)[:, 0]
        return np.where(mask.any(axis=1), best, -1).astype(np.int64)

    def _argmax(self, inputs: list[np.ndarray], mask: np.ndarray) -> int:
        # np.require: torch wants writable arrays (env observations may be shared views).
        tensors = [torch.from_numpy(np.require(x, np.float32, "CW")) for x in inputs]
        m = torch.from_numpy(np.require(mask, bool, "CW"))
        logits = self._forward(*tensors, m)
        return int(torch.where(m, logits, -torch.inf).argmax())

    def _forward(self, *inputs: torch.Tensor) -> torch.Tensor:
        if not self._traceable:
            return self.net(*inputs)
        if self._fast is None:
            with torch.jit.optimized_execution(True):
                traced = torch.jit.trace(self.net, inputs, check_trace=False)
            self._fast = torch.jit.optimize_for_inference(torch.jit.freeze(traced.eval()))
        return self._fast(*inputs)


def _take_slots(x: np.ndarray, slots: np.ndarray) -> np.ndarray:
    """Rows ``slots int [B, K]`` of a per-task entry ``x [B, N, ...]``: ``[B, K, ...]``."""
    index = slots.reshape(*slots.shape, *([1] * (x.ndim - 2)))
    return np.take_along_axis(x, index, axis=1)
