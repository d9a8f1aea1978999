"""``policy=search``: a learned checkpoint searched at decision time (:mod:`.search`).

:func:`load_search` loads a checkpoint's actor (and its critic when ``leaf > 0``) and
returns a :class:`SearchPolicy`: the network's ``width`` best slots, each rolled forward
``horizon`` decisions with the network choosing, the cheapest kept.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from rtaw_marl.errors import missing_extra

# Without the training extra: one error that names it (errors.missing_extra), no traceback
# of a bare ModuleNotFoundError.
try:
    import torch
except ModuleNotFoundError as exc:
    raise missing_extra(exc, __name__, "train") from None

from rtaw_marl.decision.features import candidate_slots, sim_observation
from rtaw_marl.models.checkpoint import Critic, load_checkpoint, load_networks
from rtaw_marl.models.rtaw_plus import RTAWPlusActor
from rtaw_marl.policies import make_baseline
from rtaw_marl.policies.config import SearchConfig
from rtaw_marl.policies.labels import checkpoint_labels
from rtaw_marl.policies.lookahead import rollout_distances
from rtaw_marl.policies.network import NetworkPolicy, checkpoint_path
from rtaw_marl.policies.search import Rollout, search_costs, top_slots
from rtaw_marl.sim.core import WarehouseSim

__all__ = ["SearchPolicy", "load_search"]


def load_search(
    source: str | Path,
    *,
    width: int = SearchConfig.width,
    horizon: int = SearchConfig.horizon,
    leaf: float = SearchConfig.leaf,
    propose: Any = None,
    name: str | None = None,
    torch_threads: int | None = 1,
    candidates: int | None = None,
) -> SearchPolicy:
    """A search policy over a checkpoint file or a shipped pretrained name.

    Args:
        source: A checkpoint path or a shipped policy's name.
        width: Slots tried per decision: the network's best ``width``.
        horizon: Decisions rolled out after each tried slot's, the network choosing.
        leaf: Weight of the critic's value of each rollout's final state (0: none).
        propose: Rules whose choices are tried too (``SearchConfig.propose``).
        name: Label in result tables; by default ``<checkpoint label>+search``.
        torch_threads: ``torch.set_num_threads``; ``None`` leaves torch as it is.
        candidates: With more queued tasks, search among the ``K`` nearest the free
            robot only (the network's ``candidates``).

    Raises:
        ConfigError: Bad ``width``/``horizon``/``leaf``, or a checkpoint that does not
            load (one line, as :func:`~rtaw_marl.policies.network.load_policy`).
    """
    SearchConfig(width=width, horizon=horizon, leaf=leaf, propose=propose)  # before loading
    path = checkpoint_path(source)
    if torch_threads is not None:
        torch.set_num_threads(int(torch_threads))
    ckpt = load_checkpoint(path)
    actor, critic = load_networks(ckpt, path)
    label = name or f"{checkpoint_labels([str(source)])[0]}+search"
    network = NetworkPolicy(actor, name=label, candidates=candidates)
    algo = (ckpt.get("config") or {}).get("algo") or {}
    return SearchPolicy(
        network, width=width, horizon=horizon, leaf=leaf, propose=propose,
        critic=critic if leaf > 0 else None, reward_scale=algo.get("reward_scale"),
    )  # fmt: skip


class SearchPolicy:
    """A network's top ``width`` slots rolled out ``horizon`` decisions (:mod:`.search`).

    Args:
        network: The learned policy that proposes the slots and chooses in rollouts
            (its ``candidates`` restricts the search to the nearest ``K`` tasks).
        width: Slots tried per decision.
        horizon: Decisions rolled out after each tried slot's.
        leaf: Weight of the critic's value of a rollout's final state.
        propose: Rules whose choices are tried too, after the network's (``None``: none).
        critic: The checkpoint's critic (needed when ``leaf > 0``).
        reward_scale: The checkpoint's ``algo.reward_scale`` (``None``: rewards were
            divided by the layout scale), to read the critic's value in cells.

    Raises:
        ConfigError: Bad ``width``/``horizon``/``leaf``.
        ValueError: ``leaf > 0`` without a critic.
    """

    def __init__(
        self,
        network: NetworkPolicy,
        *,
        width: int = SearchConfig.width,
        horizon: int = SearchConfig.horizon,
        leaf: float = SearchConfig.leaf,
        propose: Any = None,
        critic: Critic | None = None,
        reward_scale: float | None = None,
    ) -> None:
        config = SearchConfig(width=width, horizon=horizon, leaf=leaf, propose=propose)
        leaf = config.leaf
        names = [] if propose is None else [propose] if isinstance(propose, str) else propose
        self.proposers = [make_baseline(n) for n in dict.fromkeys(names)]
        if leaf > 0 and critic is None:
            raise ValueError("search with leaf > 0 needs the checkpoint's critic")
        self.network = network
        self.name = network.name
        self.width, self.horizon, self.leaf = width, horizon, float(leaf)
        self.critic = None if critic is None else critic.eval()
        self.reward_scale = reward_scale
        keys = set(network.feature_keys)
        if self.critic is not None:
            keys |= {k for k in self.critic.in_keys if k != "action_mask"}
        self._keys = tuple(sorted(keys))
        # One frozen TorchScript trace for batched calls (RTAW+; as NetworkPolicy's for
        # one decision): built at the first call, from the weights then.
        self._traceable = isinstance(network.net, RTAWPlusActor)
        self._fast: torch.jit.ScriptModule | None = None

    def reset(self, seed: int | None = None) -> None:
        """Seed the proposing rules' tie-breaking (the search itself is deterministic)."""
        for rule in self.proposers:
            rule.reset(seed)

    def act(self, observation: Any) -> int:
        """Not available: the search rolls the simulator's state forward."""
        raise NotImplementedError(
            "policy=search acts on the simulator (act_sim): its rollouts need the "
            "distance model and the robots' cells, which an observation does not hold"
        )

    @torch.no_grad()
    def act_sim(self, sim: WarehouseSim) -> int:
        """The tried slot whose rollout costs least (ties: the network's order)."""
        net = self.network
        mask = sim.queue_mask
        slots = np.arange(sim.queue_len)
        if net.candidates is not None and sim.queue_len > net.candidates:
            key = (sim.robot_distances() / sim.layout.scale).astype(np.float32)
            slots = candidate_slots(key, mask, net.candidates)
        obs = sim_observation(sim, net.feature_keys, slots)
        scores = self._scores({k: v[None] for k, v in obs.items()})[0]
        tried = top_slots(scores, obs["action_mask"], self.width)
        if self.proposers:
            tried = self._with_proposals(sim, slots, tried)
        if len(tried) == 1 or (self.horizon == 0 and self.critic is None):
            return int(slots[tried[0]])
        state = self._state(sim, slots)
        leaf = self._leaf(sim.layout.scale) if self.critic is not None else None
        cost = search_costs(state, tried, self.horizon, self._scores, self._keys, leaf)
        return int(slots[tried[int(np.argmin(cost))]])  # argmin: first of equals

    def _with_proposals(
        self, sim: WarehouseSim, slots: np.ndarray, tried: np.ndarray
    ) -> np.ndarray:
        """``tried`` (indices into ``slots``) and then each rule's choice not yet in it
        (a rule's choice outside the searched ``slots`` is left out)."""
        out = list(tried)
        for rule in self.proposers:
            where = np.flatnonzero(slots == rule.act_sim(sim))
            if len(where) and int(where[0]) not in out:
                out.append(int(where[0]))
        return np.asarray(out, dtype=np.int64)

    def _state(self, sim: WarehouseSim, slots: np.ndarray) -> Rollout:
        rows, mask = sim.queue_rows[slots], sim.queue_mask[slots]
        ends = rollout_distances(sim.distance_model, sim.robot_xy, rows, mask)
        return Rollout(
            robot=int(sim.robot), now=float(sim.time), robot_xy=sim.robot_xy,
            free_at=sim.robot_free_at, rows=rows, lengths=sim.queue_length[slots],
            mask=mask, waits=sim.queue_waits()[slots], ends=ends,
            noise_mean=float(sim.config.noise_mean), scale=float(sim.layout.scale),
        )  # fmt: skip

    @torch.no_grad()
    def _scores(self, features: dict[str, np.ndarray]) -> np.ndarray:
        """The network's logits ``float64 [B, N]`` for a batch of decisions."""
        inputs = [_tensor(features[k]) for k in self.network.feature_keys]
        mask = torch.from_numpy(np.ascontiguousarray(features["action_mask"], dtype=bool))
        if not self._traceable:
            return self.network.net(*inputs, mask).double().numpy()
        if self._fast is None:
            with torch.jit.optimized_execution(True):
                traced = torch.jit.trace(self.network.net, (*inputs, mask), check_trace=False)
            self._fast = torch.jit.optimize_for_inference(torch.jit.freeze(traced.eval()))
        return self._fast(*inputs, mask).double().numpy()

    def _leaf(self, scale: float) -> Any:
        critic = self.critic
        assert critic is not None
        # The critic's value is discounted return in reward units: -TTD / L by default.
        to_cells = 1.0 / self.reward_scale if self.reward_scale else scale

        @torch.no_grad()
        def value(features: dict[str, np.ndarray]) -> np.ndarray:
            inputs = [_tensor(features[k]) for k in critic.in_keys if k != "action_mask"]
            mask = torch.from_numpy(np.ascontiguousarray(features["action_mask"], dtype=bool))
            v = critic(*inputs, mask)[..., 0].double().numpy()
            return self.leaf * v * to_cells

        return value


def _tensor(x: np.ndarray) -> torch.Tensor:
    return torch.from_numpy(np.require(x, np.float32, "CW"))
