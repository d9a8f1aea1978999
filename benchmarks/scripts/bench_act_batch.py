"""A learned policy's decisions one at a time (``act``) against many at once
(``act_batch``): microseconds per decision.

Usage::

    python -m benchmarks.scripts.bench_act_batch            # B = 1, 8, 64, 512
    python -m benchmarks.scripts.bench_act_batch --robots 1000

Observations: ``B`` acting robots' observations of one ``warehouse_v1`` episode (open
60x60 grid, ``direct``, random tasks, N = 10), stacked as a batched env or
``observe_all()`` hands them out. For each model (``rtaw``, ``rtaw_plus``; untrained
weights, latency does not depend on them) the script times ``[act(o) for o in batch]``
and ``act_batch(batch)``, the best of ``--repeats`` timings, and prints microseconds per
decision and the ratio. torch runs on one thread.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
import torch

from rtaw_marl import warehouse_v1
from rtaw_marl.models.checkpoint import build_networks
from rtaw_marl.models.config import RTAWConfig, RTAWPlusConfig
from rtaw_marl.policies.network import NetworkPolicy


def observations(robots: int, count: int) -> list[dict]:
    """``count`` acting robots' observations (copies) of one episode."""
    env = warehouse_v1.env(
        num_robots=robots, num_tasks=count + 50, navigator="direct", tasks="random",
        layout={"name": "open", "width": 60, "height": 60},
    )  # fmt: skip
    env.reset(seed=2000)
    kept: list[dict] = []
    for _ in env.agent_iter():
        obs, *_ = env.last()
        if len(kept) == count:
            break
        kept.append(
            {
                "observation": {k: np.array(v) for k, v in obs["observation"].items()},
                "action_mask": obs["action_mask"].copy(),
            }
        )
        env.step(int(obs["action_mask"].argmax()))
    return kept


def stack(batch: list[dict]) -> dict:
    keys = batch[0]["observation"]
    return {
        "observation": {k: np.stack([o["observation"][k] for o in batch]) for k in keys},
        "action_mask": np.stack([o["action_mask"] for o in batch]),
    }


def best_us(fn, decisions: int, repeats: int) -> float:
    best = np.inf
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - start)
    return 1e6 * best / decisions


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robots", type=int, default=100)
    parser.add_argument("--sizes", type=int, nargs="+", default=[1, 8, 64, 512])
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    torch.set_num_threads(1)
    torch.manual_seed(0)
    pool = observations(args.robots, max(args.sizes))
    print(f"M = {args.robots}, N = 10; microseconds per decision (best of {args.repeats})\n")
    print("| model | B | act, one at a time | act_batch | ratio |")
    print("|---|---:|---:|---:|---:|")
    for cfg in (RTAWConfig(), RTAWPlusConfig()):
        policy = NetworkPolicy(build_networks(cfg)[0], cfg.name)
        policy.act(pool[0])  # the first call builds RTAW+'s trace
        for b in args.sizes:
            batch, stacked = pool[:b], stack(pool[:b])
            single = best_us(lambda: [policy.act(o) for o in batch], b, args.repeats)  # noqa: B023
            many = best_us(lambda: policy.act_batch(stacked), b, args.repeats)  # noqa: B023
            print(f"| {cfg.name} | {b} | {single:.1f} | {many:.1f} | {single / many:.1f}x |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
