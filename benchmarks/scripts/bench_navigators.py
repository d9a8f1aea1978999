"""Wall time of whole episodes with the collision-aware navigators (SIPP, CBS).

Two tables, printed as markdown:

* **10 robots, 50 tasks** on each 60x60 layout A-E (designated tasks, MPDM, seeds
  0-4), with ``astar`` (robots pass through each other), ``sipp`` and ``cbs``: median
  and max seconds per episode over the 25 episodes, planning calls, evacuations (idle
  or waiting robots moved aside) and CBS fallbacks (calls past ``max_nodes`` planned
  by SIPP instead), per episode. Targets: SIPP < 5 s, CBS < 30 s.
* **Scaling** on layout C (60x60) with 5 tasks per robot, M = 10 ... 100 (seeds 0-2):
  median seconds per episode and per decision.

Every episode's schedule is validated by the conflict checker (outside the timing).
One untimed warm-up episode per navigator loads the numba kernel. Run it alone: other
processes on a 2-core machine change the numbers by up to 2x.

Usage::

    .venv/bin/python -m benchmarks.scripts.bench_navigators           # about 5 minutes
    .venv/bin/python -m benchmarks.scripts.bench_navigators --quick   # a few seconds
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time

from rtaw_marl.policies import make_baseline
from rtaw_marl.sim.builder import SimSpec, build_sim
from rtaw_marl.sim.core import WarehouseSim
from rtaw_marl.sim.mapf.conflicts import check_schedule

NOISELESS = {"noise_mean": 0.0, "noise_var": 0.0}


def episode(sim: WarehouseSim, seed: int) -> dict[str, float]:
    """One MPDM episode: seconds, planning calls, evacuations, fallbacks (checked after)."""
    policy = make_baseline("mpdm")
    start = time.perf_counter()
    sim.reset(seed)
    policy.reset(seed)
    while not sim.done:
        sim.step(policy.act_sim(sim))
    seconds = time.perf_counter() - start
    stats = {"planning_calls": 0.0, "evacuations": 0.0, "cbs_fallbacks": 0.0}
    if sim.executor.collision_aware:
        check_schedule(sim.layout, sim.schedule(), expected_tasks=sim.config.num_tasks)
        stats = sim.executor.stats()
    return {
        "seconds": seconds,
        "calls": stats["planning_calls"],
        "evacuations": stats["evacuations"],
        "fallbacks": stats["cbs_fallbacks"],
        "ttd": sim.metrics().ttd,
    }


def ten_robots(layouts: str, seeds: list[int]) -> str:
    lines = [
        "| navigator | median s/episode | max s/episode | planning calls | evacuations "
        "| CBS fallbacks | mean TTD |",
        "|---|---|---|---|---|---|---|",
    ]
    keys = {"num_robots": 10, "num_tasks": 50, "queue_len": 10, **NOISELESS}
    for nav in ("astar", "sipp", "cbs"):
        runs = []
        for i, p in enumerate(layouts):
            sim = build_sim(SimSpec.of(keys, {"name": "preset", "preset": p}, nav, "designated"))
            if i == 0:
                episode(sim, 999)  # warm-up
            runs += [episode(sim, s) for s in seeds]
        secs = [r["seconds"] for r in runs]
        n = len(runs)
        lines.append(
            f"| {nav} | {statistics.median(secs):.3f} | {max(secs):.3f} "
            f"| {sum(r['calls'] for r in runs) / n:.0f} "
            f"| {sum(r['evacuations'] for r in runs) / n:.1f} "
            f"| {sum(r['fallbacks'] for r in runs) / n:.1f} "
            f"| {statistics.mean(r['ttd'] for r in runs):.0f} |"
        )
        print(lines[-1], file=sys.stderr, flush=True)
    return "\n".join(lines)


def scaling(robots: list[int], seeds: list[int], navigators: dict[str, int]) -> str:
    lines = [
        "| navigator | M | tasks | median s/episode | ms/decision | planning calls | evacuations |",
        "|---|---|---|---|---|---|---|",
    ]
    for nav, max_m in navigators.items():
        for i, m in enumerate(robots):
            if m > max_m:
                continue
            keys = {"num_robots": m, "num_tasks": 5 * m, "queue_len": 10, **NOISELESS}
            sim = build_sim(SimSpec.of(keys, {"name": "preset", "preset": "C"}, nav, "designated"))
            if i == 0:
                episode(sim, 999)
            runs = [episode(sim, s) for s in seeds]
            med = statistics.median(r["seconds"] for r in runs)
            lines.append(
                f"| {nav} | {m} | {5 * m} | {med:.2f} | {1000 * med / (5 * m):.1f} "
                f"| {statistics.mean(r['calls'] for r in runs):.0f} "
                f"| {statistics.mean(r['evacuations'] for r in runs):.1f} |"
            )
            print(lines[-1], file=sys.stderr, flush=True)
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="one layout, two seeds, M <= 25")
    args = parser.parse_args()
    if args.quick:
        print(ten_robots("C", [0, 1]))
        print(scaling([10, 25], [0], {"sipp": 25, "cbs": 10}))
        return
    print(ten_robots("ABCDE", [0, 1, 2, 3, 4]))
    print()
    print(scaling([10, 25, 50, 100], [0, 1, 2], {"sipp": 100, "cbs": 25}))


if __name__ == "__main__":
    main()
