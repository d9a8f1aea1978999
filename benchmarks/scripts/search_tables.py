"""The learned policy, alone and searched, against the best rule of every row.

Usage::

    python -m benchmarks.scripts.search_tables table1            # Table I, both modes
    python -m benchmarks.scripts.search_tables table2 default holdout unseen
    python -m benchmarks.scripts.search_tables holdout --network runs/x/best.pt --only M=3
    python -m benchmarks.scripts.search_tables table1 --render   # the tables from the data
    python -m benchmarks.scripts.search_tables table1 --render --write   # ... into docs/results.md

For each row: the best rule is chosen among
:data:`~rtaw_marl.evaluation.best_rule.DEFAULT_RULES` on the selection seeds 1000-1019
(:func:`~rtaw_marl.evaluation.best_rule.choose_best_rule`), then that rule, the network
alone and the network searched (``policy=search`` with its defaults) play the evaluation
seeds 0-19, and MPDM and ``hindsight`` too on Table I (the share). Each finished row is written
to ``benchmarks/data/search_<part>.json`` at once, so a killed run resumes where it
stopped (rows already there are kept unless ``--again``). Prints, per row, the paired
TTD differences against the best rule (positive: better) and the pooled ones.

The hold-out grid (``holdout``) was fixed before the distillation runs: robot counts
between and beyond the training ones, queue lengths of 5-50, layouts of other sizes,
the MovingAI maps in ``../shared/maps/movingai`` and LoRR's ``warehouse_large`` (TTD).
``unseen`` holds the generalist's other unseen settings (its older table's rows outside
the hold-out grid), so every row of that table has its best rule too.
"""

from __future__ import annotations

import argparse
import json
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from benchmarks.generalist import HOLDOUT_ROW, custom_scenario, shared_map, unseen_settings
from benchmarks.study import replace_section
from rtaw_marl.evaluation import evaluate
from rtaw_marl.evaluation.best_rule import choose_best_rule
from rtaw_marl.evaluation.report import markdown_table
from rtaw_marl.evaluation.stats import hindsight_share, paired_difference, pooled_difference
from rtaw_marl.policies import load_policy, make_baseline
from rtaw_marl.policies.search_policy import load_search
from rtaw_marl.scenarios import EVAL_SEEDS, ROWS, SCENARIOS, Scenario
from rtaw_marl.sim.builder import build_sim
from rtaw_marl.utils.atomic import atomic_write

ROOT = Path(__file__).resolve().parents[2]
DATA = ROOT / "benchmarks" / "data"
#: Table I and II in row order (benchmarks.tables).
TABLE1 = ("direct", "direct_m100", *(x for p in "ABCDE" for x in (f"{p}", f"{p}_m100")))
TABLE2 = tuple(f"{g}_m{m}_random" for m in (500, 1000) for g in ("open300_direct", "C256_astar"))


def table1() -> dict[str, Scenario]:
    return {
        f"{mode}|{SCENARIOS[n].title}": SCENARIOS[n].with_sim(episode_mode=mode)
        for mode in ("paper", "drain")
        for n in (ROWS[r] for r in TABLE1)
    }


def table2() -> dict[str, Scenario]:
    return {SCENARIOS[n].title: SCENARIOS[n] for n in TABLE2}


def default() -> dict[str, Scenario]:
    return {"default scenario": SCENARIOS["default"]}


def holdout() -> dict[str, Scenario]:
    """The hold-out grid (module docstring); fixed before any distillation run."""
    c, a = SCENARIOS["C_astar_m10"], SCENARIOS["A_astar_m10"]
    out = {f"layout C, M={m}": c.with_sim(num_robots=m) for m in (3, 30, 150, 300)}
    out["layout C, queue 20, M=30"] = c.with_sim(num_robots=30, queue_len=20)
    out["layout C, queue 50, M=30"] = c.with_sim(num_robots=30, queue_len=50)
    out["layout A, queue 5, M=150, paper"] = a.with_sim(
        num_robots=150, queue_len=5, episode_mode="paper"
    )
    out["120x120 B, M=100"] = custom_scenario(
        "b120", {"name": "preset", "preset": "B", "width": 120, "height": 120},
        {"num_robots": 100, "num_tasks": 1000},
    )  # fmt: skip
    out["256x256 C, M=2000"] = SCENARIOS["C256_astar_m1000_random"].with_sim(num_robots=2000)
    for name, m in (("warehouse-10-20-10-2-1", 10), ("warehouse-10-20-10-2-1", 100),
                    ("warehouse-20-40-10-2-2", 100)):  # fmt: skip
        out[f"MovingAI {name}, M={m}"] = custom_scenario(
            f"{name}_m{m}",
            shared_map("movingai", f"{name}.map"),
            {"num_robots": m, "num_tasks": 500},
        )
    out["LoRR warehouse_large, M=1000, paper"] = custom_scenario(
        "lorr_m1000", shared_map("lorr", "maps", "warehouse_large.map"),
        {"num_robots": 1000, "num_tasks": 2000, "episode_mode": "paper"},
    )  # fmt: skip
    return out


def unseen() -> dict[str, Scenario]:
    """The generalist's unseen settings (its older table) outside the hold-out grid: the
    bar of that table's rows is each setting's best rule, stored here or in ``holdout``."""
    grid = holdout()
    return {
        key: scenario
        for key, (scenario, _) in unseen_settings().items()
        if HOLDOUT_ROW.get(key, key) not in grid
    }


PARTS: dict[str, Callable[[], dict[str, Scenario]]] = {
    "table1": table1, "table2": table2, "default": default, "holdout": holdout,
    "unseen": unseen,
}  # fmt: skip


def run_row(scenario: Scenario, network: str, shares: bool) -> dict:
    """The best rule on selection seeds, then every policy on the evaluation seeds."""
    sim = build_sim(scenario.spec())
    best = choose_best_rule(sim)
    # On the evaluation seeds: the best rule, and MPDM and hindsight for the shares.
    rules = [best.name, "mpdm", "hindsight"] if shares else [best.name]
    policies = {r: make_baseline(r) for r in dict.fromkeys(rules)}
    policies["network"] = load_policy(network)
    policies["search"] = load_search(network)
    results = evaluate(sim, policies, list(EVAL_SEEDS))
    return {
        "best_rule": best.as_dict(),
        "ttd": {k: r["ttd"] for k, r in results.items()},
        "ms_per_decision": {
            k: 1e3 * float(np.sum(r["wall_time_s"]) / np.sum(r["decisions"]))
            for k, r in results.items()
        },
    }


def _diff(row: dict, base: str, other: str) -> str:
    d = paired_difference(row["ttd"][base], row["ttd"][other])
    mark = "**" if d.significant and d.mean > 0 else ""
    return f"{mark}{d.pct:+.1f}% [{d.pct_low:+.1f}, {d.pct_high:+.1f}]{mark}"


def render(part: str, rows: dict[str, dict]) -> str:
    """Markdown: per row and pooled, the network and its search against the best rule."""
    shares = part == "table1"
    head = ["setting", "best rule (selection)", "network vs best", "search vs best",
            "search vs network", "ms/decision: best, network, search"]  # fmt: skip
    if shares:
        head.append("hindsight share: network / search")
    body = []
    for key, row in rows.items():
        best = row["best_rule"]["name"]
        row = {**row, "ttd": {**row["ttd"], "best": row["ttd"][best]}}
        ms = row["ms_per_decision"]
        cells = [key.replace("|", ", "), best, _diff(row, "best", "network"),
                 _diff(row, "best", "search"), _diff(row, "network", "search"),
                 f"{ms[best]:.2f}, {ms['network']:.2f}, {ms['search']:.2f}"]  # fmt: skip
        if shares:
            cells.append(" / ".join(_share(row, p) for p in ("network", "search")))
        body.append(cells)
    lines = [markdown_table(head, body), ""]
    for who in ("network", "search"):
        pairs = [(r["ttd"][r["best_rule"]["name"]], r["ttd"][who]) for r in rows.values()]
        d = pooled_difference(pairs)
        assert d is not None
        ahead = sum(paired_difference(b, o).low > 0 for b, o in pairs)
        behind = sum(paired_difference(b, o).high < 0 for b, o in pairs)
        lines.append(
            f"- {who} vs the best rule, pooled over {len(pairs)} rows: {d.mean:+.2f}% "
            f"[{d.low:+.2f}, {d.high:+.2f}]; significantly ahead on {ahead}, behind on {behind}"
        )
        if shares:
            lines.append(f"- {who}'s hindsight share, pooled: {_pooled_share(rows, who)}")
    return "\n".join(lines)


def _share(row: dict, who: str) -> str:
    s = hindsight_share(row["ttd"]["mpdm"], row["ttd"][who], row["ttd"]["hindsight"])
    return "n/a" if s is None else f"{100 * s.share:.0f}%"


def _pooled_share(rows: dict[str, dict], who: str) -> str:
    gain = sum(np.mean(r["ttd"]["mpdm"]) - np.mean(r["ttd"][who]) for r in rows.values())
    ref = sum(np.mean(r["ttd"]["mpdm"]) - np.mean(r["ttd"]["hindsight"]) for r in rows.values())
    return f"{100 * gain / ref:.0f}%"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("parts", nargs="+", choices=list(PARTS))
    parser.add_argument("--network", default="generalist_plus")
    parser.add_argument("--only", default=None, help="rows whose key contains this")
    parser.add_argument("--again", action="store_true", help="rerun rows already stored")
    parser.add_argument("--render", action="store_true", help="print the stored tables only")
    parser.add_argument(
        "--write", action="store_true", help="also rewrite docs/results.md's search_<part> section"
    )
    args = parser.parse_args()
    for part in args.parts:
        path = DATA / f"search_{part}.json"
        stored = json.loads(path.read_text()) if path.exists() else {}
        if stored and stored.get("network") != args.network:
            raise SystemExit(f"{path} holds {stored['network']}; use --again to replace it")
        rows = dict(stored.get("rows", {}))
        for key, scenario in PARTS[part]().items():
            if args.render or (args.only and args.only not in key):
                continue
            if key in rows and not args.again:
                continue
            began = time.perf_counter()
            row = run_row(scenario, args.network, shares=part == "table1")
            print(f"{part} | {key}: {time.perf_counter() - began:.0f} s", flush=True)
            # Rows another process of this script wrote meanwhile are kept (--only splits).
            now = json.loads(path.read_text())["rows"] if path.exists() else {}
            rows = {**rows, **now, key: row}
            payload = {"network": args.network, "seeds": list(EVAL_SEEDS), "rows": rows}
            text = json.dumps(payload, indent=1) + "\n"
            atomic_write(path, lambda f, t=text: f.write(t.encode()))
        order = [k for k in PARTS[part]() if k in rows]
        if order:
            text = render(part, {k: rows[k] for k in order})
            print(f"\n## {part}\n\n{text}")
            if args.write:
                replace_section(ROOT / "docs" / "results.md", f"search_{part}", text)


if __name__ == "__main__":
    main()
