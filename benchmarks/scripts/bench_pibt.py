"""Wall time per timestep of LoRR episodes with PIBT execution, against the fleet size.

Usage::

    python -m benchmarks.scripts.bench_pibt                       # M = 100 .. 10,000, MPDM
    python -m benchmarks.scripts.bench_pibt --robots 1000 --policy lookahead
    python -m benchmarks.scripts.bench_pibt --robots 1000 10000 --turns   # LoRR's action model
    python -m benchmarks.scripts.bench_pibt --robots 10000 --turns --guidance 1   # and guide paths

LoRR's ``warehouse_large`` problem (``../shared/maps/lorr/warehouse_large_5000.json``;
the first ``M`` start cells of its agent file, random distinct cells beyond 5,000),
its reveal window (1.5 M tasks) and its task file, one core. A timestep's time is
execution (one PIBT step for the whole fleet) plus every allocation decision taken in
it. Printed per M: the start (building the simulator, the first ``M`` decisions at
``t = 0``), then the median over blocks of 50 timesteps of the steady state
(timesteps ``--warmup`` to ``--horizon``), with the slowest block, and the tasks
finished.
"""

from __future__ import annotations

import argparse
import itertools
import time
from pathlib import Path

import numpy as np

from rtaw_marl.policies import make_baseline
from rtaw_marl.scenarios import lorr_scenario
from rtaw_marl.sim.builder import build_sim

PROBLEM = (
    Path(__file__).resolve().parents[3] / "shared" / "maps" / "lorr" / "warehouse_large_5000.json"
)
BLOCK = 50


def measure(
    m: int, policy: str, horizon: int, warmup: int, turns: bool = False, guidance: float = 0.0
) -> dict[str, float]:
    """Start-up seconds and steady ms per timestep of one MPDM (or ``policy``) episode
    (robots turning as LoRR's with ``turns``; guide paths with ``guidance > 0``)."""
    start = time.perf_counter()
    scenario = lorr_scenario(
        PROBLEM, num_robots=m, horizon=horizon, starts="file" if m <= 5000 else "random",
        navigator={"name": "pibt", "record": False, "turns": turns, "guidance": guidance},
    )  # fmt: skip
    sim = build_sim(scenario.spec())
    rule = make_baseline(policy)
    sim.reset(0)
    marks: dict[int, float] = {}  # first wall time seen at or after each block boundary
    started = None
    while not sim.done:
        if started is None and sim.time > 0:
            started = time.perf_counter() - start
        t = int(sim.time)
        if t >= warmup and t % BLOCK == 0 and t not in marks:
            marks[t] = time.perf_counter()
        sim.step(rule.act_sim(sim))
    marks.setdefault(horizon, time.perf_counter())
    ts = sorted(marks)
    blocks = [1e3 * (marks[b] - marks[a]) / (b - a) for a, b in itertools.pairwise(ts)]
    return {
        "start_s": float(started or 0.0),
        "ms": float(np.median(blocks)),
        "worst_ms": float(np.max(blocks)),
        "finished": float(sim.metrics().tasks_finished),
        "total_s": time.perf_counter() - start,
        "max_stall": float(sim.executor.stats()["max_stall"]),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robots", type=int, nargs="+", default=[100, 1000, 5000, 10_000])
    parser.add_argument("--policy", default="mpdm")
    parser.add_argument("--horizon", type=int, default=600)
    parser.add_argument("--warmup", type=int, default=100)
    parser.add_argument("--turns", action="store_true", help="LoRR's action model")
    parser.add_argument("--guidance", type=float, default=0.0, help="contraflow weight")
    args = parser.parse_args()
    model = ("turns" if args.turns else "no turns") + f", guidance {args.guidance:g}"
    print(
        f"policy {args.policy}, {model}, timesteps {args.warmup}-{args.horizon} in blocks of {BLOCK}"
    )
    print("| M | start s | ms / timestep (median) | slowest block | tasks finished | total s |")
    print("|---:|---:|---:|---:|---:|---:|")
    for m in args.robots:
        r = measure(m, args.policy, args.horizon, args.warmup, args.turns, args.guidance)
        print(f"| {m:,} | {r['start_s']:.1f} | {r['ms']:.1f} | {r['worst_ms']:.1f} | "
              f"{r['finished']:,.0f} | {r['total_s']:.0f} |", flush=True)  # fmt: skip


if __name__ == "__main__":
    main()
