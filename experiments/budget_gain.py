"""What three times the budget bought: Table I's RTAW+ against its own 409,600-frame base.

Usage::

    python experiments/paper_tables.py table1 --reuse   # first: Table I with the shipped policies
    python experiments/budget_gain.py --workers 2
    python experiments/budget_gain.py --reuse   # pair again, reusing the stored base TTDs

Table I's RTAW+ column is each row's ``<scenario>_long_plus`` policy (1,228,800 PPO frames:
the ``<scenario>_plus`` run continued from its last checkpoint; the registry's
``CONTINUED``). This evaluates the base ``<scenario>_plus`` on the same rows, modes and
seeds 0-19 and pairs it per seed with the stored Table I data
(``docs/data/table1_<mode>.json``). Prints one markdown row per Table I row and mode, and
stores the base's per-seed TTDs in ``docs/data/budget_gain.json``.
"""

from __future__ import annotations

import argparse
import json
import sys
from typing import Any

import paper_tables as pt

from rtaw_marl.evaluation.stats import paired_difference
from rtaw_marl.utils.atomic import atomic_write

BASE = "RTAW+ 409,600"
SEEDS = list(range(20))  # the evaluation seeds, as Table I
HEADER = (
    "| row | mode | RTAW+ vs its base | base vs lookahead -> RTAW+ vs lookahead "
    "| hindsight share: base -> RTAW+ | base vs RTAW (both 409,600) |\n|---|---|---|---|---|---|"
)


def base_jobs(mode: str) -> list[dict[str, Any]]:
    """Table I's jobs of ``mode``, evaluating only the base RTAW+ of each row."""
    jobs = []
    for label, layout, nav, pretrained in pt.ROWS:
        for m in (10, 100):
            env = {"num_robots": m, "num_tasks": 500, "queue_len": 10, "episode_mode": mode}
            jobs.append({"key": f"{mode}|{label}, M={m}", "env": env, "layout": layout,
                         "navigator": nav, "tasks": "designated", "policies": ("RTAW+",),
                         "pretrained": {"RTAW+": pretrained[m]}, "seeds": SEEDS})  # fmt: skip
    return jobs


def stored(keys: list[str]) -> dict[str, list[float]]:
    """The base TTDs of docs/data/budget_gain.json when it holds ``keys`` on SEEDS, else {}."""
    path = pt.DATA / "budget_gain.json"
    payload = json.loads(path.read_text()) if path.is_file() else {}
    if payload.get("seeds") != SEEDS or sorted(payload.get("rows", {})) != sorted(keys):
        print(f"warning: --reuse: {path} is missing or holds other rows", file=sys.stderr)
        return {}
    return payload["rows"]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--workers", type=int, default=1, help="evaluation processes")
    parser.add_argument("--reuse", action="store_true", help="reuse docs/data/budget_gain.json")
    args = parser.parse_args()
    jobs = [*base_jobs("paper"), *base_jobs("drain")]
    results = stored([job["key"] for job in jobs]) if args.reuse else {}
    if not results:
        results = {r["key"]: r["ttd"]["RTAW+"] for r in pt.evaluated(jobs, args.workers)}
    print(HEADER)
    pooled: dict[str, list[float]] = {"base": [], "long": [], "rtaw": []}
    for mode in ("paper", "drain"):
        table = json.loads((pt.DATA / f"table1_{mode}.json").read_text())
        if table["seeds"] != SEEDS:
            raise SystemExit(f"error: table1_{mode}.json holds other seeds; regenerate Table I")
        for key, row in table["rows"].items():
            base, long = results[f"{mode}|{key}"], row["RTAW+"]
            pooled["base"] += base
            pooled["long"] += long
            pooled["rtaw"] += row["RTAW"]
            gain = paired_difference(row["lookahead"], base).pct
            print(
                f"| {key} | {mode} | {pt.vs(base, long)} | {gain:+.1f}% -> "
                f"{pt.vs(row['lookahead'], long)} | {pt.share({**row, BASE: base}, BASE)} -> "
                f"{pt.share(row, 'RTAW+')} | {pt.vs(row['RTAW'], base)} |",
                flush=True,
            )
    n = len(pooled["base"])
    print(f"\nRTAW+ vs its base, pooled: {pt.vs(pooled['base'], pooled['long'])} (n={n})")
    print(f"base vs RTAW (both 409,600), pooled: {pt.vs(pooled['rtaw'], pooled['base'])} (n={n})")
    payload = {"seeds": SEEDS, "label": BASE, "rows": results}
    text = json.dumps(payload, indent=1) + "\n"
    atomic_write(pt.DATA / "budget_gain.json", lambda fh: fh.write(text.encode()))
    return 0


if __name__ == "__main__":
    sys.exit(main())
