"""How far a training run is: the wall clock from its start, each iteration's phases, and
the time left (printed once, on the progress bar after that)."""

from __future__ import annotations

import sys
import time

from rtaw_marl.errors import missing_extra

# Without the training extra: one error that names it (errors.missing_extra), no traceback
# of a bare ModuleNotFoundError.
try:
    from tqdm import tqdm
except ModuleNotFoundError as exc:
    raise missing_extra(exc, __name__, "train") from None

from rtaw_marl.training.config import TrainConfig

__all__ = ["Clock", "Estimate", "WallClock", "duration"]


class WallClock:
    """Seconds since the run began (the rules' episodes and the warm start included),
    continued from the last evaluation's on resume."""

    def __init__(self, history: list[dict[str, float]]) -> None:
        self.offset = float(history[-1].get("wall_s", 0.0)) if history else 0.0
        self.start = time.perf_counter()

    def __call__(self) -> float:
        return self.offset + time.perf_counter() - self.start


class Clock:
    """Wall time of each phase of one iteration (logged as ``time/<phase>_s``)."""

    def __init__(self) -> None:
        self.laps: dict[str, float] = {}
        self._last = time.perf_counter()

    def lap(self, name: str) -> None:
        """Charge the time since the last lap to ``name``."""
        now = time.perf_counter()
        self.laps[name] = self.laps.get(name, 0.0) + now - self._last
        self._last = now

    def reset(self) -> None:
        """Start the next iteration: the collector's time counts from here."""
        self.laps = {}
        self._last = time.perf_counter()


class Estimate:
    """The run's remaining wall time, from the frames/s measured so far and the measured
    cost of an evaluation; :meth:`report` prints it once, after the first batches.

    Args:
        cfg: The run's config (budget and evaluation period).
        frames: Frames at the start of this session (the resume point).
    """

    #: Runs estimated to take longer than this print their estimate (seconds).
    LONG_S = 60.0
    #: Past this the estimate is a warning: the budget is likely a typo (a week).
    ABSURD_S = 7 * 24 * 3600.0
    #: Batches measured before the estimate is printed (the first includes start-up).
    BATCHES = 3

    def __init__(self, cfg: TrainConfig, frames: int) -> None:
        self.total, self.every, self.start = cfg.frames, cfg.selection.every_frames, frames
        self.batch, self.batches, self.told = cfg.algo.frames_per_batch, 0, False
        self.rate = 0.0

    def seconds(self, frames: int, totals: dict[str, float], eval_s: list[float]) -> float:
        """Seconds left at ``frames``: training at the measured rate plus the evaluations
        still due at their measured mean cost."""
        train_s = sum(v for k, v in totals.items() if k != "time/eval_checkpoint_s")
        self.rate = (frames - self.start) / max(train_s, 1e-9)
        left = self.total - frames
        per_eval = sum(eval_s) / len(eval_s) if eval_s else 0.0
        return left / self.rate + -(-left // self.every) * per_eval

    def report(self, frames: int, totals: dict[str, float], eval_s: list[float]) -> str:
        """The estimate for the progress bar; prints it once when the run is long."""
        self.batches += 1
        seconds = self.seconds(frames, totals, eval_s)
        due = self.batches >= min(self.BATCHES, -(-(self.total - self.start) // self.batch))
        if not self.told and (due or seconds > self.ABSURD_S):
            self.told = True
            if seconds > self.ABSURD_S:
                tqdm.write(
                    f"warning: frames={self.total} would take about {duration(seconds)} "
                    f"at the measured {self.rate:.0f} frames/s; Ctrl-C or SIGTERM saves and stops",
                    file=sys.stderr,
                )
            elif seconds > self.LONG_S:
                tqdm.write(
                    f"estimated time left: {duration(seconds)} ({self.total - frames} frames "
                    f"at {self.rate:.0f} frames/s, evaluations included)",
                    file=sys.stdout,
                )
        return duration(seconds)


def duration(seconds: float) -> str:
    """``45s``, ``12m05s``, ``3h07m``, ``4.2 days``, ``3.1e+04 years``."""
    if seconds < 60:
        return f"{seconds:.0f}s"
    if seconds < 3600:
        return f"{int(seconds // 60)}m{int(seconds % 60):02d}s"
    if seconds < 48 * 3600:
        return f"{int(seconds // 3600)}h{int(seconds % 3600 // 60):02d}m"
    days = seconds / 86400
    return f"{days:.1f} days" if days < 730 else f"{days / 365.25:.3g} years"
