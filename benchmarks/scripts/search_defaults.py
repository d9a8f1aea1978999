"""Choose ``policy=search``'s defaults (width, horizon, leaf) on selection seeds.

Usage::

    python -m benchmarks.scripts.search_defaults --grid wide           # generalist_plus
    python -m benchmarks.scripts.search_defaults --grid narrow         # then these
    python -m benchmarks.scripts.search_defaults --grid leaf
    python -m benchmarks.scripts.search_defaults --policy runs/x/checkpoints/best.pt
    python -m benchmarks.scripts.search_defaults --quick               # 2 settings, 5 seeds

Every (width, horizon, leaf) of the grid searches ``--policy`` on each setting (mix
members, :func:`rtaw_marl.scenarios.mix.member_spec`) over the selection seeds
1000-1009 (never an evaluation seed), beside the network alone and ``lookahead``. Prints
per setting each variant's paired TTD difference against the network alone (positive:
the search is better) and ms per decision, then the pooled difference; the variant with
the best pooled gain is the default. Per-seed values go to
``benchmarks/data/search_defaults_<grid>.json``.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from rtaw_marl.evaluation import evaluate
from rtaw_marl.evaluation.stats import pooled_difference
from rtaw_marl.policies import load_policy, make_baseline
from rtaw_marl.policies.search_policy import load_search
from rtaw_marl.scenarios.mix import member_spec
from rtaw_marl.sim.builder import build_sim
from rtaw_marl.utils.atomic import atomic_write

ROOT = Path(__file__).resolve().parents[2]
OUT = ROOT / "benchmarks" / "data" / "search_defaults.json"  # _<grid> added
#: Settings: small and large fleets, queues 5 and 10, both modes, four layouts.
SETTINGS = ("C_astar_m10", "A_astar_m100:paper", "E_astar_m100:n5", "D_astar_m10:m50:paper")
#: (width, horizon, leaf) variants of each grid, run in this order: the widths and
#: horizons first, then narrower ones around the first run's best, then the critic's
#: weight at the chosen width and horizon.
GRIDS = {
    "wide": ((2, 3, 0.0), (4, 1, 0.0), (4, 3, 0.0), (4, 5, 0.0), (8, 3, 0.0), (4, 3, 0.5)),
    "narrow": ((2, 1, 0.0), (2, 2, 0.0), (2, 3, 0.0), (2, 5, 0.0), (3, 3, 0.0), (2, 3, 0.5),
               (2, 3, 1.0)),
    "leaf": ((2, 3, 0.0), (2, 3, 0.02), (2, 3, 0.05), (2, 3, 0.1), (2, 3, 0.2)),
    # A rule's choice tried besides the network's (search.propose).
    "propose": ((2, 3, 0.0), (2, 3, 0.0, "hungarian"), (2, 3, 0.0, "mpdm"),
                (1, 3, 0.0, "hungarian"), (2, 3, 0.0, "lookahead")),
}  # fmt: skip


def label(width: int, horizon: int, leaf: float, propose: str | None = None) -> str:
    """A variant's name in the table: ``w4 h3`` (``leaf0.5``, ``+hungarian`` when used)."""
    return (
        f"w{width} h{horizon}"
        + (f" leaf{leaf:g}" if leaf else "")
        + (f" +{propose}" if propose else "")
    )


def run_setting(
    policy: str, setting: str, seeds: list[int], grid: tuple[tuple, ...]
) -> dict[str, dict[str, list[float]]]:
    """Per-seed TTD and wall time of the network, lookahead and every variant."""
    sim = build_sim(member_spec(setting))
    policies = {"network": load_policy(policy), "lookahead": make_baseline("lookahead")}
    for width, horizon, leaf, *propose in grid:
        policies[label(width, horizon, leaf, *propose)] = load_search(
            policy, width=width, horizon=horizon, leaf=leaf, propose=(propose or [None])[0]
        )
    results = evaluate(sim, policies, seeds)
    return {
        name: {"ttd": r["ttd"], "wall_time_s": r["wall_time_s"], "decisions": r["decisions"]}
        for name, r in results.items()
    }


def report(data: dict[str, dict[str, dict[str, list[float]]]]) -> str:
    """Per setting and pooled: each variant's gain over the network alone."""
    names = [n for n in next(iter(data.values())) if n != "network"]
    lines = [
        "| setting | " + " | ".join(names) + " |",
        "|---|" + "---|" * len(names),
    ]
    for setting, rows in data.items():
        base = np.asarray(rows["network"]["ttd"])
        cells = []
        for name in names:
            gain = 100 * (base - np.asarray(rows[name]["ttd"])) / base.mean()
            ms = 1e3 * np.sum(rows[name]["wall_time_s"]) / np.sum(rows[name]["decisions"])
            cells.append(f"{gain.mean():+.1f}% ({ms:.2f} ms)")
        lines.append(f"| {setting} | " + " | ".join(cells) + " |")
    pooled = []
    for name in names:
        d = pooled_difference([(r["network"]["ttd"], r[name]["ttd"]) for r in data.values()])
        assert d is not None
        pooled.append(f"{d.mean:+.2f}% [{d.low:+.2f}, {d.high:+.2f}]")
    lines.append("| pooled | " + " | ".join(pooled) + " |")
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--policy", default="generalist_plus")
    parser.add_argument("--quick", action="store_true", help="2 settings, 5 seeds")
    parser.add_argument("--grid", choices=list(GRIDS), default="narrow")
    parser.add_argument("--output", type=Path, default=None)
    args = parser.parse_args()
    settings = SETTINGS[:2] if args.quick else SETTINGS
    seeds = list(range(1000, 1005 if args.quick else 1010))
    data = {}
    for setting in settings:
        began = time.perf_counter()
        data[setting] = run_setting(args.policy, setting, seeds, GRIDS[args.grid])
        print(f"{setting}: {time.perf_counter() - began:.0f} s", flush=True)
    print(report(data))
    grid = GRIDS[args.grid]
    payload = {"policy": args.policy, "seeds": seeds, "grid": grid, "results": data}
    text = json.dumps(payload, indent=1) + "\n"
    output = args.output or OUT.with_name(f"search_defaults_{args.grid}.json")
    atomic_write(output, lambda f: f.write(text.encode()))
    print(f"per-seed values: {output}")


if __name__ == "__main__":
    main()
