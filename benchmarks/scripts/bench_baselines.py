"""Cost per decision of the rule-based policies as M (robots), N (queue) and H grow.

For each setting: a 60x60 (M <= 100) or 256x256 (M = 1000) layout-C warehouse with A*
distances and random tasks, one episode of ``decisions`` decisions played by MPDM while
each rule is asked for its choice at every decision (timed, the simulator step is not).
Prints the median milliseconds per decision over the decisions of the episode, and the
ratio to MPDM, as a markdown table. Distance fields are warmed up first (untimed).

Usage::

    .venv/bin/python -m benchmarks.scripts.bench_baselines          # about 2 minutes
    .venv/bin/python -m benchmarks.scripts.bench_baselines --quick  # a few seconds
"""

from __future__ import annotations

import argparse
import statistics
import time

from rtaw_marl.policies import BaselinesConfig, make_baseline
from rtaw_marl.sim.builder import SimSpec, build_sim
from rtaw_marl.sim.core import WarehouseSim


def _sim(m: int, n: int, decisions: int) -> WarehouseSim:
    size = 256 if m >= 1000 else 60
    layout = {"name": "preset", "preset": "C", "width": size, "height": size}
    sim_keys = {"num_robots": m, "num_tasks": decisions, "queue_len": n, "episode_mode": "paper"}
    return build_sim(SimSpec.of(sim_keys, layout, "astar", "random"))


def per_decision_ms(sim: WarehouseSim, rules: dict[str, object], seed: int) -> dict[str, float]:
    """Median milliseconds per decision of each rule's ``act_sim`` along one episode."""
    times: dict[str, list[float]] = {name: [] for name in rules}
    driver = make_baseline("mpdm")
    sim.reset(seed)
    driver.reset(seed)
    for rule in rules.values():
        rule.reset(seed)  # type: ignore[attr-defined]
    while not sim.done:
        for name, rule in rules.items():
            start = time.perf_counter()
            rule.act_sim(sim)  # type: ignore[attr-defined]
            times[name].append(1e3 * (time.perf_counter() - start))
        sim.step(driver.act_sim(sim))
    return {name: statistics.median(v) for name, v in times.items()}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--quick", action="store_true", help="small settings only")
    args = parser.parse_args()
    settings = [(10, 10), (100, 10), (10, 50)] if args.quick else [
        (10, 10), (100, 10), (1000, 10), (10, 50), (100, 50),
    ]  # fmt: skip
    horizons = [0, 3] if args.quick else [0, 3, 10]
    decisions = 60 if args.quick else 300
    print("| M | N | mpdm | rbts | hungarian | "
          + " | ".join(f"lookahead H={h}" for h in horizons) + " | hindsight H=30 |")  # fmt: skip
    print("|---|---|" + "---|" * (4 + len(horizons)))
    for m, n in settings:
        sim = _sim(m, n, decisions)
        rules = {name: make_baseline(name) for name in ("mpdm", "rbts", "hungarian")}
        for h in horizons:
            rules[f"H{h}"] = make_baseline("lookahead", params=BaselinesConfig(lookahead_horizon=h))
        if m <= 100:
            rules["hindsight"] = make_baseline("hindsight")
        per_decision_ms(sim, rules, 1)  # warm-up: distance fields, numba
        ms = per_decision_ms(sim, rules, 0)
        base = ms["mpdm"]
        cells = [f"{ms[k]:.3f} ({ms[k] / base:.0f}x)" for k in ("rbts", "hungarian")]
        cells += [f"{ms[f'H{h}']:.3f} ({ms[f'H{h}'] / base:.0f}x)" for h in horizons]
        cells.append(f"{ms['hindsight']:.1f} ({ms['hindsight'] / base:.0f}x)" if m <= 100 else "-")
        print(f"| {m} | {n} | {base:.3f} | " + " | ".join(cells) + " |", flush=True)


if __name__ == "__main__":
    main()
