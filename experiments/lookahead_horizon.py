"""Is ``lookahead``'s horizon H = 3 the strongest? Every Table I row, several horizons.

Usage::

    python experiments/lookahead_horizon.py --workers 2

``lookahead`` plays MPDM for H decisions after each candidate on the *current* queue
(no refills), so a longer horizon is not automatically better: late in a rollout the
queue runs dry and the rollout's robots grab whatever is left. This evaluates H in
``--horizons`` (default 1, 2, 3, 4, 5, 8) beside MPDM on each Table I row (500 tasks,
queue 10, ``paper`` mode) on the **selection seeds 1000-1019**, so the horizon the tables
use is chosen on other episodes than the evaluation seeds 0-19 they report. Prints one
markdown row per Table I row: each horizon's mean TTD and its paired difference against
H = 3, then the pooled difference (per-seed differences in % of each row's H = 3 mean).
"""

from __future__ import annotations

import argparse
import sys
from concurrent.futures import ProcessPoolExecutor
from typing import Any

import paper_tables as pt

from rtaw_marl.evaluation import evaluate
from rtaw_marl.policies import make_baseline
from rtaw_marl.policies.config import BaselinesConfig
from rtaw_marl.sim.builder import SimSpec

SEEDS = list(range(1000, 1020))  # selection seeds: never the evaluation seeds 0-19
REFERENCE = 3  # the horizon of the tables' lookahead (BaselinesConfig's default)


def evaluate_row(job: dict[str, Any]) -> dict[str, Any]:
    """Per-seed TTDs of MPDM and each horizon on one Table I row."""
    sim = SimSpec.of(job["env"], job["layout"], job["navigator"], "designated").build()
    policies = {"MPDM": make_baseline("mpdm", sim.navigator, sim.layout.scale)}
    for h in job["horizons"]:
        params = BaselinesConfig(lookahead_horizon=h)
        policies[f"H={h}"] = make_baseline("lookahead", sim.navigator, sim.layout.scale, params)
    res = evaluate(sim, policies, SEEDS)
    return {"key": job["key"], "ttd": {k: v["ttd"] for k, v in res.items()}}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--horizons", type=int, nargs="+", default=[1, 2, 3, 4, 5, 8])
    parser.add_argument("--workers", type=int, default=1, help="evaluation processes")
    args = parser.parse_args()
    if REFERENCE not in args.horizons or min(args.horizons) < 0:
        parser.error(f"--horizons must be >= 0 and include H = {REFERENCE}")
    jobs = []
    for label, layout, nav, _ in pt.ROWS:
        for m in (10, 100):
            env = {"num_robots": m, "num_tasks": 500, "queue_len": 10, "episode_mode": "paper"}
            jobs.append({"key": f"{label}, M={m}", "env": env, "layout": layout,
                         "navigator": nav, "horizons": args.horizons})  # fmt: skip
    labels = [f"H={h}" for h in args.horizons]
    ref = f"H={REFERENCE}"
    head = ["row", "MPDM", *labels, *(f"{h} vs {ref}" for h in labels if h != ref)]
    rows, table = [], []
    with ProcessPoolExecutor(max_workers=args.workers) as pool:
        results = list(pool.map(evaluate_row, jobs))
    for result in results:
        t = result["ttd"]
        rows.append(t)
        means = [pt.mean_cell(t, p) for p in ("MPDM", *labels)]
        table.append([result["key"], *means, *(pt.vs(t[ref], t[h]) for h in labels if h != ref)])
    print(pt.markdown(head, table))
    print(f"\nPooled against {ref} (seeds {SEEDS[0]}-{SEEDS[-1]}, 12 rows, paper mode):\n")
    for h in labels:
        if h != ref:
            print(f"- {h}: {pt.pooled(rows, ref, h)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
