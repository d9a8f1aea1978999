"""``hindsight``: a reference that knows the future, not a policy.

At each decision it tries every queued task: the free robot takes it, then MPDM plays
``horizon`` more decisions over the *real* future of the episode (the tasks still to
arrive, same-slot refills, and with instant travel the completion noise each decision
will draw). It chooses the task whose rollout has the least total travel delay. No
online policy can see that future, so the gap between MPDM and ``hindsight`` is a
practical measure of the room above MPDM; a policy's figure of merit is the share of
that gap it captures, (MPDM - policy) / (MPDM - hindsight).

Rollouts run on a shadow simulator with instant travel, loaded from the real one's
:meth:`~rtaw_marl.sim.core.WarehouseSim.state`. With a collision-aware navigator the
rollout cannot model waiting for other robots: it uses A* distances and the planned
free times, without noise.

It implements :class:`~rtaw_marl.policies.base.Policy` but acts on the simulator only:
:meth:`Hindsight.act` raises ``NotImplementedError``.

A decision costs ``N * (horizon + 1)`` simulator steps (about 1 ms per candidate at
``horizon = 30``), so a 500-decision episode takes seconds; it is meant for tables, not
for deployment.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from rtaw_marl.errors import ConfigError
from rtaw_marl.sim.core import WarehouseSim

__all__ = ["Hindsight"]


class Hindsight:
    """The hindsight reference (module docstring).

    Args:
        horizon: MPDM decisions rolled out after each candidate's own.
    """

    name = "hindsight"

    def __init__(self, horizon: int) -> None:
        if isinstance(horizon, bool) or not isinstance(horizon, int) or horizon < 0:
            raise ConfigError(f"hindsight horizon must be an integer >= 0, got {horizon!r}")
        self.horizon = horizon
        self._shadow: WarehouseSim | None = None
        self._for: WarehouseSim | None = None

    def reset(self, seed: int | None = None) -> None:
        """Nothing to seed: the choice is deterministic (ties: the lowest slot)."""

    def act(self, observation: Mapping[str, Any]) -> int:
        """Not available: the reference needs the episode's future (the tasks still to
        arrive and the noise to come), which no observation holds.

        Raises:
            NotImplementedError: Always; use :meth:`act_sim` on the simulator.
        """
        raise NotImplementedError(
            "hindsight knows the episode's future (tasks still to arrive, noise to come), "
            "which no observation holds: it acts only on the simulator, act_sim(sim)"
        )

    def act_sim(self, sim: WarehouseSim) -> int:
        """The queued task whose MPDM rollout over the real future has the least TTD."""
        shadow = self._shadow_of(sim)
        state = sim.state()
        best, best_cost = -1, np.inf
        for slot in np.flatnonzero(sim.queue_mask):
            shadow.load_state(state)
            cost = _rollout(shadow, int(slot), self.horizon)
            if cost < best_cost - 1e-9:
                best, best_cost = int(slot), cost
        return best

    def _shadow_of(self, sim: WarehouseSim) -> WarehouseSim:
        if self._for is not sim:
            # Shares the layout, the distance caches and the task stream; instant travel.
            self._shadow = WarehouseSim(sim.config, sim.layout, sim.distance_model, sim.stream)
            self._for = sim
        assert self._shadow is not None
        return self._shadow


def _rollout(shadow: WarehouseSim, slot: int, horizon: int) -> float:
    """Total TTD of ``slot`` now, then up to ``horizon`` MPDM decisions (ties: lowest slot)."""
    shadow.step(slot)
    total = shadow.last_ttd
    for _ in range(horizon):
        if shadow.done:
            break
        d = np.where(shadow.queue_mask, shadow.robot_distances(), np.inf)
        shadow.step(int(d.argmin()))
        total += shadow.last_ttd
    return total
