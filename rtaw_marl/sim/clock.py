"""A scheduler's budget per timestep: LoRR's clock in the own simulator.

LoRR gives the scheduler part of each timestep's time limit; the robots it has not
served by then wait for the next timestep. :class:`DecisionClock` counts, for the
timestep being decided, the decisions taken and the policy's wall-clock time (from a
decision's start, :meth:`DecisionClock.ask`, to its action, :meth:`DecisionClock.charge`)
and says when the budget is spent (``sim.decision_budget``, ``sim.time_budget_ms``).
"""

from __future__ import annotations

import time
from collections.abc import Callable

__all__ = ["DecisionClock"]


class DecisionClock:
    """The budget of the timestep being decided.

    Args:
        decisions: Most decisions per timestep (``None``: no limit).
        seconds: Most wall-clock seconds of the policy per timestep (``None``: no limit).
        clock: Seconds (``time.perf_counter``).
    """

    def __init__(
        self,
        decisions: int | None,
        seconds: float | None,
        clock: Callable[[], float] = time.perf_counter,
    ) -> None:
        self.decisions, self.seconds, self.clock = decisions, seconds, clock
        self.reset()

    @property
    def active(self) -> bool:
        """Whether any budget is set."""
        return self.decisions is not None or self.seconds is not None

    def reset(self) -> None:
        """Forget the timestep counted so far (a new episode)."""
        self._at, self._used, self._spent = -1.0, 0, 0.0
        self._asked_at = self.clock()

    def ask(self) -> None:
        """A decision starts now."""
        self._asked_at = self.clock()

    def charge(self, now: float) -> None:
        """The decision started by :meth:`ask` is taken, in timestep ``now``."""
        if self._at != now:
            self._at, self._used, self._spent = now, 0, 0.0
        self._used += 1
        if self.seconds is not None:
            self._spent += self.clock() - self._asked_at

    def spent(self, now: float) -> bool:
        """Whether timestep ``now``'s budget is used up."""
        if self._at != now:
            return False
        if self.decisions is not None and self._used >= self.decisions:
            return True
        return self.seconds is not None and self._spent >= self.seconds
