"""Scheduler time per timestep of a learned policy, robot by robot against matched.

Usage::

    python -m benchmarks.scripts.bench_matched                      # M = 1,000 and 5,000
    python -m benchmarks.scripts.bench_matched --robots 10000 --horizon 200
    python -m benchmarks.scripts.bench_matched --policy lorr_warehouse_plus --only matched

LoRR's ``warehouse_large`` problem as ``scenario=lorr`` runs it (turns, guidance,
reassignment; the first ``M`` start cells of its agent file, random distinct cells
beyond 5,000), one core, a shipped network (``--policy``, by default
``generalist_plus``; every RTAW+ network costs the same) with ``candidates=32``: each
free robot's decision a network call (``pretrained``), or every free robot of a timestep
from one call and a greedy matching (``matched``). Printed per M and policy: the median
and 90th percentile over timesteps ``--warmup`` to ``--horizon`` of the scheduler's time
(every ``act_sim`` of the timestep) and of the whole timestep (execution included), the
free robots per timestep and the tasks finished. LoRR gives scheduler and planner 1 s a
timestep together; issue 41's bar is 50 ms for the scheduler at 5,000 robots.
"""

from __future__ import annotations

import argparse
import itertools
import time
from pathlib import Path

import numpy as np
import torch

from rtaw_marl.policies.matched import MatchedPolicy
from rtaw_marl.policies.network import load_policy
from rtaw_marl.scenarios import lorr_scenario
from rtaw_marl.sim.builder import build_sim

PROBLEM = (
    Path(__file__).resolve().parents[3] / "shared" / "maps" / "lorr" / "warehouse_large_5000.json"
)


def measure(
    m: int, matched: bool, horizon: int, warmup: int, name: str = "generalist_plus"
) -> dict[str, float]:
    """Per-timestep scheduler and total milliseconds (median, p90) of one episode."""
    scenario = lorr_scenario(
        PROBLEM, num_robots=m, horizon=horizon, starts="file" if m <= 5000 else "random",
        navigator={"name": "pibt", "record": False},
    )  # fmt: skip
    sim = build_sim(scenario.spec())
    network = load_policy(name, candidates=32)
    policy = MatchedPolicy(network) if matched else network
    sim.reset(0)
    policy.reset(0)
    spent: dict[int, float] = {}
    free: dict[int, int] = {}
    wall: dict[int, float] = {}
    while not sim.done:
        t = int(sim.time)
        if t not in wall:
            wall[t] = time.perf_counter()
            free[t] = len(sim.free_robots())
        start = time.perf_counter()
        slot = policy.act_sim(sim)
        spent[t] = spent.get(t, 0.0) + time.perf_counter() - start
        sim.step(slot)
    steps = sorted(wall)
    total = {t: wall[b] - wall[t] for t, b in itertools.pairwise(steps)}
    keep = [t for t in steps if warmup <= t < horizon - 1 and t in total]
    sched = 1e3 * np.array([spent.get(t, 0.0) for t in keep])
    whole = 1e3 * np.array([total[t] for t in keep])
    return {
        "sched_median": float(np.median(sched)),
        "sched_p90": float(np.percentile(sched, 90)),
        "total_median": float(np.median(whole)),
        "total_p90": float(np.percentile(whole, 90)),
        "free": float(np.median([free[t] for t in keep])),
        "first_s": spent.get(0, 0.0),
        "tasks": float(sim.metrics().tasks_finished),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robots", type=int, nargs="+", default=[1000, 5000])
    parser.add_argument("--horizon", type=int, default=300)
    parser.add_argument("--warmup", type=int, default=100)
    parser.add_argument("--policy", default="generalist_plus", help="a shipped network")
    parser.add_argument("--only", choices=("robot_by_robot", "matched"), default=None)
    args = parser.parse_args()
    torch.set_num_threads(1)
    print(
        "| robots | policy | scheduler ms/timestep (median, p90) | timestep ms (median, p90) "
        "| free robots / timestep | t = 0 s | tasks |"
    )
    print("|---:|---|---:|---:|---:|---:|---:|")
    for m in args.robots:
        for matched in (False, True):
            if args.only is not None and matched != (args.only == "matched"):
                continue
            r = measure(m, matched, args.horizon, args.warmup, args.policy)
            name = "matched" if matched else "robot by robot"
            print(
                f"| {m:,} | {name} | {r['sched_median']:.1f}, {r['sched_p90']:.1f} | "
                f"{r['total_median']:.1f}, {r['total_p90']:.1f} | {r['free']:.0f} | "
                f"{r['first_s']:.1f} | {r['tasks']:,.0f} |",
                flush=True,
            )


if __name__ == "__main__":
    main()
