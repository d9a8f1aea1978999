"""PIBT with and without priority rotation on the LoRR start kit's random 32x32 problem.

Usage::

    python -m benchmarks.scripts.pibt_rotation

100 robots, MPDM, seeds 0-4, 5,000 timesteps; an episode in which no robot reaches a
goal for 200 timesteps stops (``navigator.stall_limit=200``). Rotation off is
``navigator.patience`` = 10^9. Prints, per setting, each seed's outcome: the tasks
finished, or the timestep at which it deadlocked.
"""

from __future__ import annotations

from pathlib import Path

from rtaw_marl.errors import PlanningError
from rtaw_marl.evaluation.evaluate import run_episode
from rtaw_marl.policies import make_baseline
from rtaw_marl.scenarios import lorr_scenario
from rtaw_marl.sim.builder import build_sim

KIT = Path(__file__).resolve().parents[3] / "shared" / "lorr" / "start-kit-v2.1.2"
PROBLEM = KIT / "example_problems" / "random.domain" / "random_32_32_20_100.json"


def main() -> None:
    for label, patience in (("rotation off", 10**9), ("rotation on (default)", 16)):
        outcomes = []
        for seed in range(5):
            # The turn-free model without guidance, where the measurement was made.
            nav = {"name": "pibt", "stall_limit": 200, "patience": patience, "record": False,
                   "turns": False, "guidance": 0.0}  # fmt: skip
            sim = build_sim(lorr_scenario(PROBLEM, navigator=nav).spec())
            try:
                run_episode(sim, make_baseline("mpdm"), seed=seed)
                outcomes.append(f"{sim.metrics().tasks_finished:,} finished")
            except PlanningError:
                outcomes.append(f"deadlock at t={sim.executor.t}")
        print(f"{label}: " + "; ".join(outcomes), flush=True)


if __name__ == "__main__":
    main()
