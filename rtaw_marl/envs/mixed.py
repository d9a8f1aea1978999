"""Simulators of several scenarios in one batched TorchRL env: what a generalist trains on.

:class:`MixedBatchedEnv` holds one :class:`~rtaw_marl.envs.torchrl.BatchedWarehouseEnv`
per member scenario (its own layout, navigator, task stream, fleet size ``M_j``, queue
length ``N_j`` and episode length) and stacks their decisions into one batch of
``B = sum(counts)``. That works because RTAW+'s inputs do not depend on ``M``:

* ``"relations"`` float32 ``[B, N, 8]``, ``"rivals"`` ``[B, N, K, 4]``, ``"tasks"``
  ``[B, N, 6]``, ``"agent"`` ``[B, 3]``, ``"fleet"`` ``[B, 8]`` and ``"action_mask"``
  bool ``[B, N]``, with ``N = max N_j``: a member with a shorter queue has its extra
  slots empty (masked, features zero). ``"robots"`` (``[M, 3]``) is refused.
* ``("next", "reward")`` float32 ``[B, 1]``: minus the chosen task's TTD divided by the
  member's layout scale ``L_j`` (the features' unit), so that a 300x300 grid's rewards
  do not drown a 60x60 grid's; :attr:`scale` is therefore 1.
* ``"done"``, ``"terminated"``, ``"truncated"`` ``[B, 1]``, per simulator.

Member ``j``'s simulators are rows ``offsets[j] .. offsets[j + 1] - 1``; they draw their
episode seeds as a lone batched env seeded ``seed * J + j`` would (never a seed reserved
for results). Finished simulators are reset by TorchRL's ``_reset`` mechanism.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence

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
    from torchrl.envs import EnvBase
except ModuleNotFoundError as exc:
    raise missing_extra(exc, __name__, "train") from None

from rtaw_marl.envs.torchrl import DONE_KEYS, BatchedWarehouseEnv, set_batch_specs
from rtaw_marl.sim.builder import SimSpec

__all__ = ["MIXED_KEYS", "MixedBatchedEnv"]

#: The observation entries a mix can stack (every one but ``robots``).
MIXED_KEYS = ("tasks", "agent", "relations", "rivals", "fleet")
#: Entries with a queue-slot axis (padded to the longest queue).
_SLOTTED = frozenset({"tasks", "relations", "rivals", "action_mask"})


class MixedBatchedEnv(EnvBase):
    """Simulators of several scenarios as one TorchRL env with batch size ``[B]``.

    Args:
        members: ``(spec, count)`` per member scenario: ``count`` simulators of ``spec``.
        seed: Base seed of the episode seeds.
        keys: Observation entries (of :data:`MIXED_KEYS`; ``action_mask`` always).

    Raises:
        ConfigError: No member, a count below 1, or ``robots`` (or an unknown key) among
            ``keys``.
    """

    def __init__(
        self,
        members: Sequence[tuple[SimSpec, int]],
        seed: int = 0,
        keys: Iterable[str] = ("relations", "rivals", "fleet"),
    ) -> None:
        keys = tuple(k for k in dict.fromkeys(keys) if k != "action_mask")
        if not members:
            raise ConfigError("a mix needs at least one member scenario")
        if bad := [k for k in keys if k not in MIXED_KEYS]:
            raise ConfigError(
                f"a mix cannot stack observation key(s) {bad} (their size depends on the "
                f"fleet); valid: {', '.join(MIXED_KEYS)}"
            )
        if any(int(count) < 1 for _, count in members):
            raise ConfigError(f"every mix member needs >= 1 simulator, got {members!r}")
        self.parts = [BatchedWarehouseEnv(spec, int(c), keys=keys) for spec, c in members]
        self.keys = keys
        counts = [part.num_envs for part in self.parts]
        self.offsets = np.concatenate([[0], np.cumsum(counts)]).astype(int)
        b = int(self.offsets[-1])
        self.num_envs, self.queue_len = b, max(part.queue_len for part in self.parts)
        #: Rewards are already in units of each member's ``L``.
        self.scale = 1.0
        super().__init__(batch_size=torch.Size([b]), device="cpu")
        self._obs: list[TensorDict | None] = [None] * len(self.parts)
        self._live, self._closed = False, False
        self._set_seed(seed)
        set_batch_specs(self, self.keys, b, 1, self.queue_len)  # no key has an M axis

    @property
    def sims(self) -> list:
        """Every simulator, in batch order."""
        return [sim for part in self.parts for sim in part.sims]

    @property
    def episode_seeds(self) -> np.ndarray:
        """``int64 [B]``: the seed of each simulator's current episode."""
        return np.concatenate([part.episode_seeds for part in self.parts])

    def _set_seed(self, seed: int | None) -> None:
        base = 0 if seed is None else int(seed)
        for j, part in enumerate(self.parts):
            part._set_seed(base * len(self.parts) + j)

    def _reset(self, tensordict: TensorDictBase | None = None, **kwargs: object) -> TensorDictBase:
        if kwargs:
            raise EnvUsageError(
                f"reset() got unknown keyword arguments {sorted(kwargs)}; seed the env with "
                "set_seed(seed)"
            )
        if self._closed:
            raise usage_error("env.reset()", closed=True)
        which = None
        if tensordict is not None and "_reset" in tensordict.keys():  # noqa: SIM118
            which = tensordict["_reset"].reshape(self.num_envs)
        for j, part in enumerate(self.parts):
            lo, hi = self.offsets[j], self.offsets[j + 1]
            if which is None or self._obs[j] is None:
                self._obs[j] = part._reset()
            elif bool(which[lo:hi].any()):
                sub = TensorDict({"_reset": which[lo:hi, None]}, batch_size=[hi - lo])
                self._obs[j] = part._reset(sub)
        self._live = True
        out = self._stacked(self._obs)
        zeros = torch.zeros((self.num_envs, 1), dtype=torch.bool)
        out.update({key: zeros.clone() for key in DONE_KEYS})
        return out

    def _step(self, tensordict: TensorDictBase) -> TensorDictBase:
        if not self._live:
            raise usage_error("env.step()", self._closed)
        action = tensordict["action"].reshape(self.num_envs)
        outs = []
        for j, part in enumerate(self.parts):
            lo, hi = self.offsets[j], self.offsets[j + 1]
            try:
                out = part._step(TensorDict({"action": action[lo:hi]}, batch_size=[hi - lo]))
            except InvalidActionError as exc:
                raise InvalidActionError(f"mix member {j} (rows {lo}-{hi - 1}): {exc}") from None
            out["reward"] = out["reward"] / part.scale
            outs.append(out)
        self._obs = [out.select(*self.keys, "action_mask") for out in outs]
        stacked = self._stacked(outs)
        for key in ("reward", *DONE_KEYS):
            stacked[key] = torch.cat([out[key] for out in outs])
        return stacked

    def _stacked(self, outs: Sequence[TensorDictBase]) -> TensorDict:
        """The members' observations as one batch, queues padded to ``N``."""
        n = self.queue_len
        data = {}
        for key in (*self.keys, "action_mask"):
            data[key] = torch.cat([_padded(key, out[key], n) for out in outs])
        self._action_spec_unbatched.update_mask(data["action_mask"])
        return TensorDict(data, batch_size=self.batch_size)

    def close(self, *, raise_if_closed: bool = True) -> None:
        """Close the env and its members."""
        for part in self.parts:
            part.close(raise_if_closed=False)
        self._live, self._closed = False, True
        super().close(raise_if_closed=raise_if_closed)


def _padded(key: str, values: torch.Tensor, n: int) -> torch.Tensor:
    """``values [b, N_j, ...]`` of a slotted key with empty (zero / ``False``) slots
    appended up to ``n``; ``agent`` and ``fleet`` (no slot axis) as they are."""
    if key not in _SLOTTED or values.shape[1] == n:
        return values
    pad = torch.zeros((values.shape[0], n - values.shape[1], *values.shape[2:]), dtype=values.dtype)
    return torch.cat([values, pad], dim=1)
