"""What three times the budget bought, for both networks: Table I's policies against their
own 409,600-frame bases.

Usage::

    python experiments/paper_tables.py table1 --reuse   # first: Table I with the shipped policies
    python experiments/budget_gain.py --workers 2
    python experiments/budget_gain.py --reuse   # pair again, reusing the stored base TTDs

Table I's columns are each row's ``<scenario>_long`` (the paper's network, RTAW) and
``<scenario>_long_plus`` (RTAW+) policies, 1,228,800 PPO frames each: the 409,600-frame
run ``<scenario>`` / ``<scenario>_plus`` continued from its last checkpoint (the
registry's ``CONTINUED``). This evaluates both bases on the same rows, modes and seeds
0-19 and pairs them per seed with the stored Table I data
(``docs/data/table1_<mode>.json``). Prints one markdown row per Table I row and mode, then
pooled lines (per-seed differences in % of each row's baseline mean, as paper_tables),
and stores the bases' per-seed TTDs in ``docs/data/budget_gain.json`` (``{"seeds": [...],
"rows": {"<mode>|<row>": {"RTAW": [...], "RTAW+": [...]}}}``).
"""

from __future__ import annotations

import argparse
import json
import sys
from typing import Any

import paper_tables as pt

from rtaw_marl.utils.atomic import atomic_write

SEEDS = list(range(20))  # the evaluation seeds, as Table I
NETS = ("RTAW", "RTAW+")
#: The base of a Table I column: its label in the paired rows.
BASE = {"RTAW": "RTAW 1x", "RTAW+": "RTAW+ 1x"}
HEADER = (
    "| row | mode | RTAW+: 3x vs 1x | RTAW: 3x vs 1x | RTAW+ vs RTAW at 1x | RTAW+ vs RTAW at 3x "
    "| hindsight share 1x -> 3x: RTAW / RTAW+ |\n|---|---|---|---|---|---|---|"
)


def base_jobs(mode: str) -> list[dict[str, Any]]:
    """Table I's jobs of ``mode``, evaluating only the two bases of each row."""
    jobs = []
    for label, layout, nav, pretrained in pt.ROWS:
        for m in (10, 100):
            env = {"num_robots": m, "num_tasks": 500, "queue_len": 10, "episode_mode": mode}
            jobs.append({"key": f"{mode}|{label}, M={m}", "env": env, "layout": layout,
                         "navigator": nav, "tasks": "designated", "policies": NETS,
                         "pretrained": pretrained[m], "seeds": SEEDS})  # fmt: skip
    return jobs


def stored(keys: list[str]) -> dict[str, pt.Ttd]:
    """The base TTDs of docs/data/budget_gain.json when it holds ``keys`` on SEEDS, else {}."""
    path = pt.DATA / "budget_gain.json"
    payload = json.loads(path.read_text()) if path.is_file() else {}
    rows = payload.get("rows", {})
    if payload.get("seeds") != SEEDS or sorted(rows) != sorted(keys):
        print(f"warning: --reuse: {path} is missing or holds other rows", file=sys.stderr)
        return {}
    return rows


def paired_rows(results: dict[str, pt.Ttd]) -> dict[str, pt.Ttd]:
    """Each ``"<mode>|<row>"``: Table I's stored TTDs plus the bases (:data:`BASE` labels)."""
    rows = {}
    for mode in ("paper", "drain"):
        table = json.loads((pt.DATA / f"table1_{mode}.json").read_text())
        if table["seeds"] != SEEDS:
            raise SystemExit(f"error: table1_{mode}.json holds other seeds; regenerate Table I")
        for key, row in table["rows"].items():
            bases = results[f"{mode}|{key}"]
            rows[f"{mode}|{key}"] = {**row, **{BASE[n]: bases[n] for n in NETS}}
    return rows


def line(key: str, t: pt.Ttd) -> str:
    mode, row = key.split("|", 1)
    shares = " / ".join(f"{pt.share(t, BASE[n])} -> {pt.share(t, n)}" for n in NETS)
    return (
        f"| {row} | {mode} | {pt.vs(t['RTAW+ 1x'], t['RTAW+'])} | {pt.vs(t['RTAW 1x'], t['RTAW'])} "
        f"| {pt.vs(t['RTAW 1x'], t['RTAW+ 1x'])} | {pt.vs(t['RTAW'], t['RTAW+'])} | {shares} |"
    )


def pooled_lines(rows: list[pt.Ttd]) -> list[str]:
    lines = [
        f"- RTAW+ 3x vs 1x: {pt.pooled(rows, 'RTAW+ 1x', 'RTAW+')}",
        f"- RTAW 3x vs 1x: {pt.pooled(rows, 'RTAW 1x', 'RTAW')}",
        f"- RTAW+ vs RTAW at 1x: {pt.pooled(rows, 'RTAW 1x', 'RTAW+ 1x')}",
        f"- RTAW+ vs RTAW at 3x: {pt.pooled(rows, 'RTAW', 'RTAW+')}",
    ]
    for label in (*BASE.values(), *NETS):
        strongest = pt.pooled(rows, pt.STRONGEST, label)
        lines.append(
            f"- {label} vs MPDM: {pt.pooled(rows, 'MPDM', label)}; vs the strongest rule: "
            f"{strongest}; hindsight share {pt.percent(pt.pooled_share(rows, label))}"
        )
    return lines


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--workers", type=int, default=1, help="evaluation processes")
    parser.add_argument("--reuse", action="store_true", help="reuse docs/data/budget_gain.json")
    args = parser.parse_args()
    jobs = [*base_jobs("paper"), *base_jobs("drain")]
    results = stored([job["key"] for job in jobs]) if args.reuse else {}
    if not results:
        results = {r["key"]: r["ttd"] for r in pt.evaluated(jobs, args.workers)}
    rows = paired_rows(results)
    print(HEADER)
    for key, t in rows.items():
        print(line(key, t), flush=True)
    print("\nPooled over both modes (n = row-seed pairs):\n")
    print("\n".join(pooled_lines(list(rows.values()))))
    text = json.dumps({"seeds": SEEDS, "rows": results}, indent=1) + "\n"
    atomic_write(pt.DATA / "budget_gain.json", lambda fh: fh.write(text.encode()))
    return 0


if __name__ == "__main__":
    sys.exit(main())
