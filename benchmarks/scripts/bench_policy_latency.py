"""Latency of a learned policy's decision, on one core: features, network, total, and
the rules it must not be slower than.

Usage::

    python -m benchmarks.scripts.bench_policy_latency            # every row below
    python -m benchmarks.scripts.bench_policy_latency --quick    # M = 10 and 1000, fewer decisions

Rows: M = 10, 100, 1000 on a 256x256 layout C, and M = 1000 and 10,000 on LoRR's
``warehouse_large`` (500x140, ``../shared/maps/lorr/maps``; skipped when absent), A*,
random tasks, ``paper`` episodes (every decision has a full queue of N = 10). For each
model (``rtaw``, ``rtaw_plus``; untrained weights: latency does not depend on them) the
script plays MPDM along one episode and, at every decision, times the learned policy's
observation features (``sim_observation``), its network on the path ``act_sim`` takes
(RTAW+: a frozen TorchScript trace), the whole greedy ``act_sim``, MPDM's and
``lookahead``'s ``act_sim``, and ``policy=search`` over RTAW+ (its default width and
horizon) beside ``lookahead`` and ``hungarian``. Prints median milliseconds per decision
(the best of 3 timings of each) and the ratios to MPDM and lookahead. torch runs on one
thread.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
import torch

from rtaw_marl.decision.features import sim_observation
from rtaw_marl.models.checkpoint import build_networks
from rtaw_marl.models.config import RTAWConfig, RTAWPlusConfig
from rtaw_marl.policies import MPDM, make_baseline
from rtaw_marl.policies.network import NetworkPolicy
from rtaw_marl.policies.search_policy import SearchPolicy
from rtaw_marl.sim.builder import SimSpec, build_sim
from rtaw_marl.sim.core import WarehouseSim

LORR = Path(__file__).resolve().parents[3] / "shared" / "maps" / "lorr" / "maps"
C256 = {"name": "preset", "preset": "C", "width": 256, "height": 256}


def _sim(m: int, decisions: int, layout: dict) -> WarehouseSim:
    sim_keys = {"num_robots": m, "num_tasks": decisions, "queue_len": 10, "episode_mode": "paper"}
    return build_sim(SimSpec.of(sim_keys, layout, "astar", "random"))


def _ms(fn, repeat: int = 3) -> float:
    best = np.inf
    for _ in range(repeat):
        start = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - start)
    return 1e3 * best


@torch.no_grad()
def measure(m: int, decisions: int, layout: dict) -> dict[str, dict[str, float]]:
    """Median ms per decision of each phase, per model, along one MPDM episode."""
    torch.manual_seed(0)
    policies = {
        cfg.name: NetworkPolicy(build_networks(cfg)[0], cfg.name)
        for cfg in (RTAWConfig(), RTAWPlusConfig())
    }
    sim, mpdm, lookahead = _sim(m, decisions, layout), MPDM(), make_baseline("lookahead")
    sim.reset(0)
    times: dict[str, dict[str, list[float]]] = {
        name: {"features": [], "network": [], "total": []} for name in policies
    }
    rule: list[float] = []
    ahead: list[float] = []
    # policy=search over RTAW+ with its defaults, and hungarian: the rules it must match.
    search = SearchPolicy(policies["rtaw_plus"])
    hungarian = make_baseline("hungarian")
    searched: list[float] = []
    matched: list[float] = []
    while not sim.done:
        for name, policy in policies.items():
            keys = policy.net.in_keys
            obs = sim_observation(sim, keys)
            args = [torch.from_numpy(obs[k]) for k in keys]
            times[name]["features"].append(_ms(lambda k=keys: sim_observation(sim, k)))
            times[name]["network"].append(_ms(lambda p=policy, a=args: p._forward(*a)))
            times[name]["total"].append(_ms(lambda p=policy: p.act_sim(sim)))
        rule.append(_ms(lambda: mpdm.act_sim(sim)))
        ahead.append(_ms(lambda: lookahead.act_sim(sim)))
        searched.append(_ms(lambda: search.act_sim(sim)))
        matched.append(_ms(lambda: hungarian.act_sim(sim)))
        sim.step(mpdm.act_sim(sim))
    out = {name: {k: float(np.median(v)) for k, v in t.items()} for name, t in times.items()}
    out["mpdm"] = {"total": float(np.median(rule))}
    out["lookahead"] = {"total": float(np.median(ahead))}
    out["search"] = {"total": float(np.median(searched))}
    out["hungarian"] = {"total": float(np.median(matched))}
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--quick", action="store_true", help="M = 10 and 1000 on 256x256 C, 30 decisions"
    )
    args = parser.parse_args()
    torch.set_num_threads(1)
    decisions = 30 if args.quick else 100
    rows = [(10, "256x256 C", C256), (1000, "256x256 C", C256)]
    if not args.quick:
        rows.insert(1, (100, "256x256 C", C256))
        big = LORR / "warehouse_large.map"
        if big.is_file():
            lorr = {"name": "file", "path": str(big)}
            rows += [(1000, "warehouse_large", lorr), (10_000, "warehouse_large", lorr)]
    print(
        "| layout | M | N | model | features ms | network ms | total ms | MPDM ms | "
        "lookahead ms | total / MPDM | total / lookahead |"
    )
    print("|---|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|")
    search_rows = []
    for m, label, layout in rows:
        res = measure(m, decisions, layout)
        search_rows.append((label, m, res))
        rule, ahead = res["mpdm"]["total"], res["lookahead"]["total"]
        for name in ("rtaw", "rtaw_plus"):
            r = res[name]
            print(f"| {label} | {m} | 10 | {name} | {r['features']:.3f} | {r['network']:.3f} | "
                  f"{r['total']:.3f} | {rule:.3f} | {ahead:.3f} | {r['total'] / rule:.0f}x | "
                  f"{r['total'] / ahead:.2f}x |", flush=True)  # fmt: skip
    print("\npolicy=search (RTAW+, its default width and horizon) against the rules:\n")
    print("| layout | M | N | search ms | lookahead ms | hungarian ms | search / lookahead |")
    print("|---|---:|---:|---:|---:|---:|---:|")
    for label, m, res in search_rows:
        t, ahead, hung = (
            res["search"]["total"],
            res["lookahead"]["total"],
            res["hungarian"]["total"],
        )
        print(f"| {label} | {m} | 10 | {t:.3f} | {ahead:.3f} | {hung:.3f} | {t / ahead:.2f}x |")


if __name__ == "__main__":
    main()
