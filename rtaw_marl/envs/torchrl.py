"""A native, batched TorchRL env: ``B`` warehouse simulators stepped together.

The shared RTAW policy sees a single decision stream per simulator: at every step each
of the ``B`` simulators has one free robot that must be given a task. The batch is what
makes training fast on a CPU: TorchRL's per-step overhead (about 0.5 ms) is paid once
for ``B`` decisions, and the observation features of all simulators are computed by one
vectorised expression over shared ``[B, ...]`` state buffers (see
:class:`rtaw_marl.sim.core.SimBuffers`).

Keys (batch size ``[B]``):

* ``"robots"`` float32 ``[B, M, 3]``, ``"tasks"`` float32 ``[B, N, 6]``, ``"agent"``
  float32 ``[B, 3]``, ``"relations"`` float32 ``[B, N, 8]``, ``"rivals"`` float32
  ``[B, N, K, 4]``, ``"action_mask"`` bool ``[B, N]``: exactly the PettingZoo env's
  observation of the free robot (same feature functions, bit-identical).
* ``"action"`` int64 ``[B]``: the chosen slot. A non-integer tensor, or a slot out of
  range or empty, raises :class:`~rtaw_marl.errors.InvalidActionError` naming the
  simulator, before any simulator steps.
* With ``candidates=K`` (fewer than ``N`` slots): each decision holds only the ``K``
  queued tasks whose origins are nearest the free robot
  (:func:`~rtaw_marl.decision.features.candidate_slots`, the slots a
  ``NetworkPolicy(candidates=K)`` scores), ``N`` is ``K`` in every key above, and the
  action is an index into them (:attr:`BatchedWarehouseEnv.candidate_slots` maps it to
  the slot). LoRR's windows hold ``1.5 M`` tasks: without it, the network's attention
  over all of them is ``[B, H, N, N]``.
* ``("next", "reward")`` float32 ``[B, 1]``: minus the chosen task's TTD (or the
  ablation reward), unscaled.
* ``"done"``, ``"terminated"``, ``"truncated"`` bool ``[B, 1]``: ``drain`` episodes
  terminate, ``paper`` episodes are truncated.

Finished simulators are reset by TorchRL's ``_reset`` mechanism (collectors do it
automatically). Simulator ``b`` draws its episode seeds from
``numpy.random.default_rng([seed, b])``, never a seed reserved for results (0-1999,
:data:`~rtaw_marl.sim.inputs.RESERVED_SEEDS`); :attr:`episode_seeds` holds the seeds of the
current episodes, so any episode can be replayed in the PettingZoo env.

Misuse raises the project's errors: ``step`` (and :meth:`episode_metrics`) before the
first reset :class:`~rtaw_marl.errors.ResetNeededError`, anything after ``close()``
:class:`~rtaw_marl.errors.EnvUsageError`, as do keyword arguments to ``reset`` (TorchRL
hands them to ``_reset``, and none is known here: seeds come from ``set_seed`` and
:meth:`reset_to`) and an :meth:`episode_metrics` index outside ``0..B-1``.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

import numpy as np

from rtaw_marl.errors import (
    ConfigError,
    EnvUsageError,
    InvalidActionError,
    missing_extra,
    usage_error,
)

# Without the training extra: one error that names it (errors.missing_extra), no traceback
# of a bare ModuleNotFoundError.
try:
    import torch
    from tensordict import TensorDict, TensorDictBase
    from torchrl.data import Binary, Categorical, Composite, Unbounded
    from torchrl.envs import EnvBase
except ModuleNotFoundError as exc:
    raise missing_extra(exc, __name__, "train") from None

from rtaw_marl.decision.features import (
    ALL_KEYS,
    FEATURES,
    OBSERVATION_KEYS,
    RELATIONAL_KEYS,
    Decision,
    candidate_slots,
    decision_features,
    feature_shapes,
)
from rtaw_marl.sim.builder import SimFactory, SimSpec
from rtaw_marl.sim.config import SimBuffers
from rtaw_marl.sim.inputs import draw_training_seed, seed_value

__all__ = ["DONE_KEYS", "OBSERVATION_KEYS", "BatchedWarehouseEnv", "set_batch_specs"]

#: The done flags of every step, ``bool [B, 1]`` each.
DONE_KEYS = ("done", "terminated", "truncated")


def set_batch_specs(env: EnvBase, keys: Iterable[str], b: int, m: int, n: int) -> None:
    """Give ``env`` (batch ``[b]``) the specs of a warehouse decision stream: the
    observation entries ``keys`` for ``M = m`` robots and ``N = n`` slots, the masked
    slot action, the reward and the done flags (``_action_spec_unbatched`` is the action
    spec whose mask each observation updates)."""
    shapes = feature_shapes(m, n)
    env.observation_spec = Composite(
        {key: Unbounded(shape=(b, *shapes[key]), dtype=torch.float32) for key in keys},
        action_mask=Binary(n=n, shape=(b, n), dtype=torch.bool),
        shape=(b,),
    )
    env.action_spec = Categorical(n, shape=(b,), dtype=torch.int64)
    env._action_spec_unbatched = env.full_action_spec["action"]
    env.reward_spec = Unbounded(shape=(b, 1), dtype=torch.float32)
    env.done_spec = Composite(
        {key: Categorical(2, shape=(b, 1), dtype=torch.bool) for key in DONE_KEYS}, shape=(b,)
    )


class BatchedWarehouseEnv(EnvBase):
    """``num_envs`` warehouse simulators as one TorchRL env with batch size ``[num_envs]``.

    Args:
        spec: The simulator spec (:class:`~rtaw_marl.sim.builder.SimSpec`); the layout,
            distance model and task stream are built once and shared by all simulators.
        num_envs: ``B``.
        seed: Base seed of the episode seeds.
        keys: The observation entries to compute and return (``action_mask`` always):
            any of :data:`~rtaw_marl.decision.features.ALL_KEYS`, by default the five of
            :data:`~rtaw_marl.decision.features.FEATURES`. A trainer asks for what its
            networks read: RTAW+ with ``model.fleet_summary`` needs no ``[B, M, ...]``
            entry, so neither the env's cost nor a batch's size grows with ``M``.
        candidates: ``K``: each decision holds the ``K`` nearest queued tasks only (the
            module docstring); ``None`` (or ``K >= N``): every slot.

    Raises:
        ConfigError: ``num_envs < 1``, ``candidates < 1``, or an unknown key (the
            message lists them).
    """

    def __init__(
        self,
        spec: SimSpec,
        num_envs: int,
        seed: int = 0,
        keys: Iterable[str] = FEATURES,
        candidates: int | None = None,
    ) -> None:
        if int(num_envs) < 1:
            raise ConfigError(f"num_envs must be >= 1, got {num_envs}")
        if candidates is not None and (
            isinstance(candidates, bool) or not isinstance(candidates, int) or candidates < 1
        ):
            raise ConfigError(f"candidates must be an integer >= 1 or None, got {candidates!r}")
        self.keys = tuple(k for k in dict.fromkeys(keys) if k != "action_mask")
        if unknown := [k for k in self.keys if k not in ALL_KEYS]:
            raise ConfigError(f"unknown observation key(s) {unknown}; valid: {', '.join(ALL_KEYS)}")
        super().__init__(batch_size=torch.Size([num_envs]), device="cpu")
        # Live from the first reset to close(); one flag read per batched step.
        self._live, self._closed = False, False
        # Only the distances the keys need are gathered (the fleet's is [M, N]).
        self._own = "tasks" in self.keys
        self._relational = bool(set(RELATIONAL_KEYS) & set(self.keys))
        factory = SimFactory(spec)
        b, m, n = int(num_envs), spec.sim.num_robots, spec.sim.queue_len
        self.num_envs, self.num_robots, self.queue_len = b, m, n
        self.scale = factory.layout.scale
        #: ``K`` when decisions hold candidates only, else ``None``.
        self.candidates = candidates if candidates is not None and candidates < n else None
        w = n if self.candidates is None else self.candidates
        #: ``int64 [B, K]``: the slot of each action index (``arange(N)`` without
        #: ``candidates``).
        self.candidate_slots = np.broadcast_to(np.arange(w), (b, w)).copy()
        self._robot_xy = np.zeros((b, m, 2), dtype=np.int64)
        self._free_at = np.zeros((b, m), dtype=np.float64)
        self._mask = np.zeros((b, n), dtype=bool)
        self._rows = np.zeros((b, n, 4), dtype=np.int64)
        self._length = np.zeros((b, n), dtype=np.float64)
        self._time = np.zeros(b, dtype=np.float64)
        self._robot = np.zeros(b, dtype=np.int64)
        self._dist = np.zeros((b, w), dtype=np.float64)
        self._all_dist = np.zeros((b, m, w), dtype=np.float64)
        self._nearest = np.zeros((b, w), dtype=np.float64)
        self._wait = np.zeros((b, w), dtype=np.float64)
        self.sims = [
            factory(
                SimBuffers(
                    self._robot_xy[i],
                    self._free_at[i],
                    self._mask[i],
                    self._rows[i],
                    self._length[i],
                )
            )
            for i in range(b)
        ]
        self.episode_seeds = np.zeros(b, dtype=np.int64)
        self._set_seed(seed)
        set_batch_specs(self, self.keys, b, m, w)

    # ------------------------------------------------------------------ seeding
    def _set_seed(self, seed: int | None) -> None:
        base = 0 if seed is None else seed_value(seed)
        self._seed_rngs = [np.random.default_rng([base, i]) for i in range(self.num_envs)]

    # ------------------------------------------------------------------ reset / step
    def _reset(self, tensordict: TensorDictBase | None = None, **kwargs: Any) -> TensorDictBase:
        if kwargs:
            raise EnvUsageError(
                f"reset() got unknown keyword arguments {sorted(kwargs)}; seed the env with "
                "set_seed(seed) or reset_to(seeds)"
            )
        if tensordict is not None and "_reset" in tensordict.keys():  # noqa: SIM118
            which = np.flatnonzero(tensordict["_reset"].reshape(self.num_envs).numpy())
        else:
            which = range(self.num_envs)
        return self._reset_sims({int(i): draw_training_seed(self._seed_rngs[i]) for i in which})

    def _step(self, tensordict: TensorDictBase) -> TensorDictBase:
        if not self._live:
            raise usage_error("env.step()", self._closed)
        slots = self._checked_slots(tensordict["action"])
        reward = np.empty((self.num_envs, 1), dtype=np.float32)
        done = np.zeros((self.num_envs, 1), dtype=bool)
        truncated = np.zeros((self.num_envs, 1), dtype=bool)
        for i, (sim, slot) in enumerate(zip(self.sims, slots, strict=True)):
            if sim.done:
                # An ended episode ignores its action until it is reset, so episodes of
                # different lengths (horizon episodes) can run in lockstep.
                reward[i, 0], done[i, 0], truncated[i, 0] = 0.0, True, sim.truncated
                continue
            try:
                reward[i, 0] = sim.step(slot)
            except InvalidActionError as exc:
                raise InvalidActionError(f"simulator {i}: {exc}") from None
            if sim.done:
                done[i, 0] = True
                truncated[i, 0] = sim.truncated
            else:
                self._sync(i)
        out = self._observation()
        out.update(
            {
                "reward": torch.from_numpy(reward),
                "done": torch.from_numpy(done),
                "terminated": torch.from_numpy(done & ~truncated),
                "truncated": torch.from_numpy(truncated),
            }
        )
        return out

    def _checked_slots(self, action: torch.Tensor) -> list[int]:
        """The batch's actions as ints, checked at once before any simulator steps.

        Raises:
            InvalidActionError: ``action`` is not an integer tensor of ``B`` slots, or a
                slot is out of range or empty (the message names the first simulator).
        """
        if action.dtype.is_floating_point or action.dtype.is_complex or action.dtype == torch.bool:
            raise InvalidActionError(f"action must be an integer tensor, got {action.dtype}")
        if action.numel() != self.num_envs:
            raise InvalidActionError(
                f"action must hold {self.num_envs} slots, got shape {tuple(action.shape)}"
            )
        index = action.reshape(self.num_envs).numpy()
        width = self.candidate_slots.shape[1]
        in_range = (index >= 0) & (index < width)
        rows = np.arange(self.num_envs)
        slots = self.candidate_slots[rows, np.where(in_range, index, 0)]
        legal = in_range & self._mask[rows, slots]
        legal |= np.array([sim.done for sim in self.sims])  # ignored (see _step)
        if not legal.all():
            i = int(np.flatnonzero(~legal)[0])
            what = "queue slot" if self.candidates is None else "candidate"
            problem = (
                f"is not a {what} (0..{width - 1})" if not in_range[i] else f"names an empty {what}"
            )
            raise InvalidActionError(f"simulator {i}: action {int(index[i])} {problem}")
        return slots.tolist()

    def reset_to(self, seeds: list[int] | np.ndarray) -> TensorDictBase:
        """Reset every simulator with an explicit episode seed (for evaluation).

        Args:
            seeds: One seed per simulator, ``[B]``.

        Returns:
            The observation tensordict, as :meth:`reset` gives.
        """
        seeds = [seed_value(s, "reset_to seed") for s in seeds]
        if len(seeds) != self.num_envs:
            raise ConfigError(f"reset_to needs {self.num_envs} seeds, got {len(seeds)}")
        return self._reset_sims(dict(enumerate(seeds)))

    def _reset_sims(self, seeds: dict[int, int]) -> TensorDictBase:
        """Reset simulator ``i`` with ``seeds[i]`` for each key; observe the whole batch."""
        if self._closed:
            raise usage_error("env.reset()", closed=True)
        for i, seed in seeds.items():
            self.episode_seeds[i] = seed
            self.sims[i].reset(seed)
            self._sync(i)
        self._live = True
        out = self._observation()
        zeros = torch.zeros((self.num_envs, 1), dtype=torch.bool)
        out.update({"done": zeros, "terminated": zeros.clone(), "truncated": zeros.clone()})
        return out

    def _sync(self, i: int) -> None:
        """Copy simulator ``i``'s per-decision scalars and distances into the batch arrays."""
        sim = self.sims[i]
        self._time[i] = sim.time
        self._robot[i] = sim.robot
        if self.candidates is not None:
            self._sync_candidates(i)
            return
        if self._own:
            self._dist[i] = sim.robot_distances()
        if self._relational:
            # The simulator's kept arrays, copied once, into the batch.
            self._all_dist[i] = sim.distance_matrix(copy=False)
            self._nearest[i] = sim.chain_nearest(copy=False)
            self._wait[i] = sim.queue_waits()

    def _sync_candidates(self, i: int) -> None:
        """Simulator ``i``'s candidates (NetworkPolicy's key: distance / L in float32)
        and their distances."""
        sim = self.sims[i]
        own = sim.robot_distances()
        key = (own / self.scale).astype(np.float32)
        slots = candidate_slots(key, sim.queue_mask, self.candidates)
        self.candidate_slots[i] = slots
        self._dist[i] = own[slots]
        if self._relational:
            self._all_dist[i] = sim.distance_matrix(slots)
            self._nearest[i] = sim.chain_nearest(slots)
            self._wait[i] = sim.queue_waits()[slots]

    def _observation(self) -> TensorDict:
        rows, length, mask = self._rows, self._length, self._mask
        if self.candidates is not None:
            slots = self.candidate_slots
            rows = np.take_along_axis(rows, slots[..., None], axis=1)
            length = np.take_along_axis(length, slots, axis=1)
            mask = np.take_along_axis(mask, slots, axis=1)
        decision = Decision(
            self._robot_xy, self._free_at, self._time, self._robot, rows, length, mask,
            self.scale, own_distances=self._dist, distances=self._all_dist, waits=self._wait,
            nearest=self._nearest,
        )  # fmt: skip
        features = decision_features(decision, self.keys)
        mask = torch.from_numpy(features["action_mask"])
        # A masked action spec makes random policies (and check_env_specs) pick valid slots.
        self._action_spec_unbatched.update_mask(mask)
        return TensorDict(
            {key: torch.from_numpy(features[key]) for key in (*self.keys, "action_mask")},
            batch_size=self.batch_size,
        )

    # ------------------------------------------------------------------ results
    def episode_metrics(self, i: int) -> dict[str, float | int]:
        """Metrics of simulator ``i``'s current (or just finished) episode.

        Raises:
            EnvUsageError: ``i`` is not in ``0..B-1``, or the env was never reset or is
                closed.
        """
        if not self._live:
            raise usage_error("env.episode_metrics()", self._closed)
        if (
            isinstance(i, bool)
            or not isinstance(i, (int, np.integer))
            or not 0 <= i < self.num_envs
        ):
            raise EnvUsageError(
                f"episode_metrics: no simulator {i!r}; the env has {self.num_envs} "
                f"(0..{self.num_envs - 1})"
            )
        return self.sims[i].metrics().as_dict()

    def close(self, *, raise_if_closed: bool = True) -> None:
        """Close the env: every later ``reset`` or ``step`` raises :class:`EnvUsageError`."""
        self._live, self._closed = False, True
        super().close(raise_if_closed=raise_if_closed)
