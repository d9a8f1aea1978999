"""Latency of a learned policy's decision, on one core: features, network, total.

Usage::

    python experiments/bench_policy_latency.py            # M = 10, 100, 1000; N = 10
    python experiments/bench_policy_latency.py --quick    # M = 10 and 1000, fewer decisions

For each model (``rtaw``, ``rtaw_plus``; untrained weights: latency does not depend on
them) and robot count, plays MPDM along one ``paper``-mode episode on a 256x256 layout C
with A* and random tasks (so every decision has a full queue) and, at every decision,
times the learned policy's observation features (``sim_observation``), its network
forward pass, and the whole greedy ``act_sim``. Prints the median milliseconds per
decision and the ratio of the total to MPDM's decision. torch runs on one thread.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
import torch

from rtaw_marl.envs.features import sim_observation
from rtaw_marl.models.checkpoint import build_networks
from rtaw_marl.models.config import RTAWConfig, RTAWPlusConfig
from rtaw_marl.policies import MPDM
from rtaw_marl.policies.network import NetworkPolicy
from rtaw_marl.sim.builder import SimSpec, build_sim
from rtaw_marl.sim.core import WarehouseSim


def _sim(m: int, decisions: int) -> WarehouseSim:
    layout = {"name": "preset", "preset": "C", "width": 256, "height": 256}
    env = {"num_robots": m, "num_tasks": decisions, "queue_len": 10, "episode_mode": "paper"}
    return build_sim(SimSpec.of(env, layout, "astar", "random"))


def _ms(fn, repeat: int = 3) -> float:
    best = np.inf
    for _ in range(repeat):
        start = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - start)
    return 1e3 * best


@torch.no_grad()
def measure(m: int, decisions: int) -> dict[str, dict[str, float]]:
    """Median ms per decision of each phase, per model, along one MPDM episode."""
    torch.manual_seed(0)
    policies = {
        cfg.name: NetworkPolicy(build_networks(cfg)[0], cfg.name)
        for cfg in (RTAWConfig(), RTAWPlusConfig())
    }
    sim, mpdm = _sim(m, decisions), MPDM()
    sim.reset(0)
    times: dict[str, dict[str, list[float]]] = {
        name: {"features": [], "network": [], "total": []} for name in policies
    }
    rule: list[float] = []
    while not sim.done:
        for name, policy in policies.items():
            keys = policy.net.in_keys
            obs = sim_observation(sim, keys)
            args = [torch.from_numpy(obs[k]) for k in keys]
            times[name]["features"].append(_ms(lambda k=keys: sim_observation(sim, k)))
            times[name]["network"].append(_ms(lambda p=policy, a=args: p.net(*a)))
            times[name]["total"].append(_ms(lambda p=policy: p.act_sim(sim)))
        rule.append(_ms(lambda: mpdm.act_sim(sim)))
        sim.step(mpdm.act_sim(sim))
    out = {name: {k: float(np.median(v)) for k, v in t.items()} for name, t in times.items()}
    out["mpdm"] = {"total": float(np.median(rule))}
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="M = 10 and 1000, 30 decisions")
    args = parser.parse_args()
    torch.set_num_threads(1)
    robots, decisions = ((10, 1000), 30) if args.quick else ((10, 100, 1000), 100)
    print("| M | N | model | features ms | network ms | total ms | total / MPDM |")
    print("|---|---|---|---|---|---|---|")
    for m in robots:
        res = measure(m, decisions)
        for name in ("rtaw", "rtaw_plus"):
            r = res[name]
            ratio = r["total"] / res["mpdm"]["total"]
            print(f"| {m} | 10 | {name} | {r['features']:.3f} | {r['network']:.3f} | "
                  f"{r['total']:.3f} | {ratio:.0f}x |", flush=True)  # fmt: skip


if __name__ == "__main__":
    main()
