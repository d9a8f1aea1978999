"""Per-decision latency of RTAW+ against the queue length ``N``, scoring every task or
the ``K`` nearest (``candidates=K``), on one core.

Usage::

    python -m benchmarks.scripts.bench_candidates              # N = 10 .. 2000, K = 32
    python -m benchmarks.scripts.bench_candidates --k 16 --robots 100

256x256 layout C, A*, random tasks, ``paper`` episodes (the queue is always full), the
shipped ``generalist_plus``. Along one MPDM episode the script times, at every decision,
``act_sim`` of the policy on the whole queue and with ``candidates=K``, and MPDM's
``act_sim`` (the best of 3 timings each). Prints median milliseconds and the ratios.
torch runs on one thread.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
import torch

from rtaw_marl.policies import MPDM
from rtaw_marl.policies.network import load_policy
from rtaw_marl.sim.builder import SimSpec, build_sim

C256 = {"name": "preset", "preset": "C", "width": 256, "height": 256}


def _ms(fn, repeat: int = 3) -> float:
    best = np.inf
    for _ in range(repeat):
        start = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - start)
    return 1e3 * best


def measure(m: int, n: int, k: int, decisions: int) -> dict[str, float]:
    """Median ms per decision: the policy on all ``n`` tasks, on ``k``, and MPDM."""
    sim_keys = {"num_robots": m, "num_tasks": decisions, "queue_len": n, "episode_mode": "paper"}
    sim = build_sim(SimSpec.of(sim_keys, C256, "astar", "random"))
    full = load_policy("generalist_plus")
    top = load_policy("generalist_plus", candidates=k)
    mpdm = MPDM()
    sim.reset(0)
    times: dict[str, list[float]] = {"full": [], "top": [], "mpdm": []}
    while not sim.done:
        times["full"].append(_ms(lambda: full.act_sim(sim)))
        times["top"].append(_ms(lambda: top.act_sim(sim)))
        times["mpdm"].append(_ms(lambda: mpdm.act_sim(sim)))
        sim.step(mpdm.act_sim(sim))
    return {key: float(np.median(v)) for key, v in times.items()}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--k", type=int, default=32, help="candidates scored")
    parser.add_argument("--robots", type=int, default=1000, help="M")
    parser.add_argument("--decisions", type=int, default=60)
    args = parser.parse_args()
    torch.set_num_threads(1)
    print(f"| M | N | all N ms | K = {args.k} ms | MPDM ms | all / K | K / MPDM |")
    print("|---:|---:|---:|---:|---:|---:|---:|")
    for n in (10, 100, 500, 2000):
        r = measure(args.robots, n, args.k, args.decisions)
        ratios = f"{r['full'] / r['top']:.1f}x | {r['top'] / r['mpdm']:.0f}x"
        print(f"| {args.robots} | {n} | {r['full']:.2f} | {r['top']:.2f} | {r['mpdm']:.3f} | "
              f"{ratios} |", flush=True)  # fmt: skip


if __name__ == "__main__":
    main()
