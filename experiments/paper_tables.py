"""Regenerate the results tables of docs/results.md, with paired 95% intervals.

Usage::

    python experiments/paper_tables.py table1      # Table I, paper and drain modes
    python experiments/paper_tables.py table2 --no-hindsight   # Table II: 5,000 tasks
    python experiments/paper_tables.py table2_hindsight --seeds 5   # its hindsight column
    python experiments/paper_tables.py transfer    # cross-layout transfer of the zoo
    python experiments/paper_tables.py navigators  # SIPP and CBS execution
    python experiments/paper_tables.py table1 --seeds 5 --workers 2   # quicker, 2 processes

Every table is evaluated on the evaluation seeds 0-19 (``--seeds N``: 0..N-1); the
pretrained policies were trained and selected on other seeds. Each row evaluates MPDM,
RBTS, ``lookahead`` (H = 3), ``hungarian``, the ``hindsight`` reference (knows the
future; ``--no-hindsight`` leaves it out) and the shipped RTAW policy, and reports:

* mean TTD per policy;
* RTAW against MPDM and against the strongest rule of that row (the rule with the lowest
  mean TTD among RBTS, lookahead and hungarian): the paired difference in % of that
  policy's mean, its 95% Student t-interval over seeds, ``*`` where it excludes 0;
* the share of the hindsight gain over MPDM that lookahead and RTAW capture.

Pooled rows average the per-seed differences of every row (each in % of its row's
baseline mean) with a t-interval over all row-seed pairs. The script replaces its
section of docs/results.md (between ``<!-- BEGIN name -->`` and ``<!-- END name -->``)
and writes the per-seed TTDs to docs/data/<name>.json.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

import numpy as np

from rtaw_marl.evaluation import evaluate
from rtaw_marl.evaluation.stats import hindsight_share, paired_difference
from rtaw_marl.policies import make_baseline
from rtaw_marl.policies.network import load_policy
from rtaw_marl.policies.pretrained.registry import pretrained_path
from rtaw_marl.sim.builder import SimSpec

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "docs" / "results.md"
DATA = ROOT / "docs" / "data"
RULES = ("RBTS", "lookahead", "hungarian")

#: Table I rows: label, layout spec, navigator, pretrained policy per robot count.
ROWS = [
    ("Direct (open 60x60)", {"name": "open", "width": 60, "height": 60}, "direct",
     {10: "open60_direct_m10", 100: "open60_direct_m100"}),
    *[
        (f"A* layout {p}", {"name": "preset", "preset": p, "width": 60, "height": 60}, "astar",
         {10: f"{p}_astar_m10", 100: f"{p}_astar_m10"})
        for p in "ABCDE"
    ],
]  # fmt: skip


# --------------------------------------------------------------------------- evaluation
def evaluate_setting(job: dict[str, Any]) -> dict[str, Any]:
    """Evaluate every policy on one setting; returns per-seed TTDs and seconds/episode."""
    sim = SimSpec.of(job["env"], job["layout"], job["navigator"], job["tasks"]).build()
    names = {"MPDM": "mpdm", "RBTS": "rbts", "lookahead": "lookahead", "hungarian": "hungarian"}
    if job.get("hindsight", True):
        names["hindsight"] = "hindsight"
    policies: dict[str, Any] = {
        label: make_baseline(name, sim.navigator, sim.layout.scale)
        for label, name in names.items()
        if label in job.get("only", names)
    }
    if job.get("pretrained"):
        policies["RTAW"] = load_policy(pretrained_path(job["pretrained"]), name="RTAW")
    res = evaluate(sim, policies, job["seeds"])
    return {
        "key": job["key"],
        "ttd": {k: v["ttd"] for k, v in res.items()},
        "seconds": {k: float(np.mean(v["wall_time_s"])) for k, v in res.items()},
    }


def run_all(jobs: list[dict[str, Any]], workers: int) -> dict[Any, dict[str, Any]]:
    """Every job, on ``workers`` processes, keyed by ``job["key"]``; prints progress."""
    out = {}
    with ProcessPoolExecutor(max_workers=workers) as pool:
        for result in pool.map(evaluate_setting, jobs):
            out[result["key"]] = result
            print(f"done {result['key']}", file=sys.stderr, flush=True)
    return out


# --------------------------------------------------------------------------- cells
def vs(base: list[float], other: list[float]) -> str:
    """``+3.1% [+1.2, +5.0]*``: ``other``'s TTD below ``base``'s, paired over seeds."""
    d = paired_difference(base, other)
    if d.pct_low is None:
        return f"{d.pct:+.1f}%"
    mark = "*" if d.significant else ""
    return f"{d.pct:+.1f}% [{d.pct_low:+.1f}, {d.pct_high:+.1f}]{mark}"


def share(ttd: dict[str, list[float]], name: str) -> str:
    if "hindsight" not in ttd:
        return "-"
    s = hindsight_share(ttd["MPDM"], ttd[name], ttd["hindsight"])
    return "-" if s is None else f"{100 * s.share:.0f}%"


def strongest_rule(ttd: dict[str, list[float]]) -> str:
    return min(RULES, key=lambda r: float(np.mean(ttd[r])))


def pooled(pairs: list[tuple[list[float], list[float]]]) -> str:
    """Per-seed differences of every row, each in % of its row's baseline mean."""
    diffs = np.concatenate([100 * (np.asarray(b) - np.asarray(o)) / np.mean(b) for b, o in pairs])
    zeros = np.zeros_like(diffs)
    d = paired_difference(diffs, zeros)  # the interval of the mean of the differences
    mark = "*" if d.significant else ""
    return f"{d.mean:+.1f}% [{d.low:+.1f}, {d.high:+.1f}]{mark} (n={d.n})"


def policy_table(
    results: dict[Any, dict[str, Any]], labels: list[tuple[Any, str]], extra: str = ""
) -> tuple[str, list[str]]:
    """Rows of mean TTDs and comparisons; returns the table and the pooled lines."""
    order = [p for p in ("MPDM", *RULES, "hindsight", "RTAW")]
    head = ["setting", *order, "RTAW vs MPDM", "RTAW vs strongest rule", "hindsight share:"
            " lookahead / RTAW"]  # fmt: skip
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    to_mpdm, to_best, look_mpdm, look_best = [], [], [], []
    for key, label in labels:
        ttd = results[key]["ttd"]
        best = strongest_rule(ttd)
        cells = [label, *(f"{np.mean(ttd[p]):.0f}" if p in ttd else "-" for p in order)]
        cells += [vs(ttd["MPDM"], ttd["RTAW"]), f"{best}: {vs(ttd[best], ttd['RTAW'])}"]
        cells.append(f"{share(ttd, 'lookahead')} / {share(ttd, 'RTAW')}")
        lines.append("| " + " | ".join(cells) + " |")
        to_mpdm.append((ttd["MPDM"], ttd["RTAW"]))
        to_best.append((ttd[best], ttd["RTAW"]))
        look_mpdm.append((ttd["MPDM"], ttd["lookahead"]))
        if best != "lookahead":
            look_best.append((ttd[best], ttd["lookahead"]))
    summary = [
        f"- RTAW vs MPDM, pooled: {pooled(to_mpdm)}",
        f"- RTAW vs the strongest rule of each row, pooled: {pooled(to_best)}",
        f"- lookahead vs MPDM, pooled: {pooled(look_mpdm)}",
    ]
    return "\n".join(lines) + extra, summary


# --------------------------------------------------------------------------- tables
def table1(mode: str, seeds: list[int], workers: int, hindsight: bool) -> str:
    jobs, labels = [], []
    for label, layout, nav, pretrained in ROWS:
        for m in (10, 100):
            env = {"num_robots": m, "num_tasks": 500, "queue_len": 10, "episode_mode": mode}
            key = f"{label}, M={m}"
            jobs.append({"key": key, "env": env, "layout": layout, "navigator": nav,
                         "tasks": "designated", "pretrained": pretrained[m], "seeds": seeds,
                         "hindsight": hindsight})  # fmt: skip
            labels.append((key, key))
    results = run_all(jobs, workers)
    save(f"table1_{mode}", results, seeds)
    table, summary = policy_table(results, labels)
    return table + "\n\n" + "\n".join(summary)


def table2(seeds: list[int], workers: int, hindsight: bool) -> str:
    settings = [
        ("Direct, open 300x300", {"name": "open", "width": 300, "height": 300}, "direct",
         "open300_direct_m100_random"),
        ("A*, layout C 256x256", {"name": "preset", "preset": "C", "width": 256, "height": 256},
         "astar", "C256_astar_m100_random"),
    ]  # fmt: skip
    jobs, labels = [], []
    for m in (500, 1000):
        for label, layout, nav, pretrained in settings:
            env = {"num_robots": m, "num_tasks": 5000, "queue_len": 10, "episode_mode": "paper"}
            key = f"M={m}, {label}"
            # Random tasks over the whole grid: the designated centres of the 60x60
            # setting would leave most of a 256x256 or 300x300 grid unused.
            jobs.append({"key": key, "env": env, "layout": layout, "navigator": nav,
                         "tasks": "random", "pretrained": pretrained, "seeds": seeds,
                         "hindsight": hindsight})  # fmt: skip
            labels.append((key, key))
    results = run_all(jobs, workers)
    save("table2", results, seeds)
    table, summary = policy_table(results, labels)
    wall = ["", "Seconds per episode (mean over seeds):", ""]
    for key, _ in labels:
        secs = results[key]["seconds"]
        wall.append(f"- {key}: " + ", ".join(f"{k} {v:.1f}" for k, v in secs.items()))
    return table + "\n\n" + "\n".join(summary) + "\n" + "\n".join(wall)


TABLE2_SETTINGS = [
    ("Direct, open 300x300", {"name": "open", "width": 300, "height": 300}, "direct"),
    ("A*, layout C 256x256", {"name": "preset", "preset": "C", "width": 256, "height": 256},
     "astar"),
]  # fmt: skip


def table2_hindsight(seeds: list[int], workers: int) -> str:
    """The hindsight reference on Table II's first seeds (about a minute per episode at
    1,000 robots), against the policies' TTDs of ``docs/data/table2.json``."""
    saved = json.loads((DATA / "table2.json").read_text())["rows"]
    jobs = []
    for m in (500, 1000):
        for label, layout, nav in TABLE2_SETTINGS:
            env = {"num_robots": m, "num_tasks": 5000, "queue_len": 10, "episode_mode": "paper"}
            jobs.append({"key": f"M={m}, {label}", "env": env, "layout": layout,
                         "navigator": nav, "tasks": "random", "seeds": seeds,
                         "only": ("hindsight",)})  # fmt: skip
    results = run_all(jobs, workers)
    n = len(seeds)
    lines = ["| setting | seeds | MPDM | lookahead | RTAW | hindsight | hindsight share: "
             "lookahead / RTAW |", "|---|---|---|---|---|---|---|"]  # fmt: skip
    for key, res in results.items():
        ttd = {k: v[:n] for k, v in saved[key].items()}
        ttd["hindsight"] = res["ttd"]["hindsight"]
        cells = [f"{np.mean(ttd[p]):.0f}" for p in ("MPDM", "lookahead", "RTAW", "hindsight")]
        lines.append(f"| {key} | 0-{n - 1} | " + " | ".join(cells)
                     + f" | {share(ttd, 'lookahead')} / {share(ttd, 'RTAW')} |")  # fmt: skip
    return "\n".join(lines)


def transfer(seeds: list[int], workers: int) -> str:
    """Each layout's pretrained policy on every layout (M = 10, A*, drain), vs MPDM."""
    presets = "ABCDE"
    jobs = []
    for p in presets:
        layout = {"name": "preset", "preset": p, "width": 60, "height": 60}
        env = {"num_robots": 10, "num_tasks": 500}
        jobs.append({"key": ("MPDM", p), "env": env, "layout": layout, "navigator": "astar",
                     "tasks": "designated", "seeds": seeds, "only": ("MPDM",)})  # fmt: skip
        for trained in presets:
            jobs.append({"key": (trained, p), "env": env, "layout": layout,
                         "navigator": "astar", "tasks": "designated", "seeds": seeds,
                         "only": (), "pretrained": f"{trained}_astar_m10"})  # fmt: skip
    results = run_all(jobs, workers)
    header = "| trained on \\ evaluated on | " + " | ".join(presets) + " |"
    lines = [header, "|" + "---|" * (len(presets) + 1)]
    for trained in presets:
        cells = [
            vs(results[("MPDM", p)]["ttd"]["MPDM"], results[(trained, p)]["ttd"]["RTAW"])
            for p in presets
        ]
        lines.append(f"| {trained} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def navigators(seeds: list[int], workers: int, hindsight: bool) -> str:
    """10 robots, 50 designated tasks on layouts A-E, with A*, SIPP and CBS execution."""
    env = {"num_robots": 10, "num_tasks": 50, "queue_len": 10, "noise_mean": 0.0, "noise_var": 0.0}
    jobs, labels = [], []
    for nav in ("astar", "sipp", "cbs"):
        for p in "ABCDE":
            layout = {"name": "preset", "preset": p, "width": 60, "height": 60}
            key = f"{p}, {nav}"
            jobs.append({"key": key, "env": env, "layout": layout, "navigator": nav,
                         "tasks": "designated", "pretrained": f"{p}_astar_m10",
                         "seeds": seeds, "hindsight": hindsight})  # fmt: skip
            labels.append((key, key))
    results = run_all(jobs, workers)
    save("navigators", results, seeds)
    table, _ = policy_table(results, labels)
    summary = []
    for nav in ("astar", "sipp", "cbs"):
        rows = [results[f"{p}, {nav}"]["ttd"] for p in "ABCDE"]
        rtaw_mpdm = pooled([(t["MPDM"], t["RTAW"]) for t in rows])
        rtaw_rbts = pooled([(t["RBTS"], t["RTAW"]) for t in rows])
        look_mpdm = pooled([(t["MPDM"], t["lookahead"]) for t in rows])
        summary.append(
            f"- {nav}, pooled over A-E: RTAW vs MPDM {rtaw_mpdm}; vs RBTS {rtaw_rbts}; "
            f"lookahead vs MPDM {look_mpdm}"
        )
    return table + "\n\n" + "\n".join(summary)


# --------------------------------------------------------------------------- files
def save(name: str, results: dict[Any, dict[str, Any]], seeds: list[int]) -> None:
    DATA.mkdir(parents=True, exist_ok=True)
    payload = {"seeds": seeds, "rows": {str(k): v["ttd"] for k, v in results.items()}}
    (DATA / f"{name}.json").write_text(json.dumps(payload, indent=1) + "\n")


def replace_section(name: str, body: str) -> None:
    """Replace the text between the section's markers in docs/results.md."""
    text = RESULTS.read_text()
    begin, end = f"<!-- BEGIN {name} -->", f"<!-- END {name} -->"
    if begin not in text or end not in text:
        raise SystemExit(f"docs/results.md has no {begin} ... {end} markers")
    head, rest = text.split(begin, 1)
    _, tail = rest.split(end, 1)
    stamp = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())
    RESULTS.write_text(f"{head}{begin}\n_Generated {stamp}._\n\n{body}\n{end}{tail}")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument(
        "table", choices=["table1", "table2", "table2_hindsight", "transfer", "navigators"]
    )
    parser.add_argument("--seeds", type=int, default=20, help="evaluate on seeds 0..N-1")
    parser.add_argument("--workers", type=int, default=1, help="evaluation processes")
    parser.add_argument("--no-hindsight", action="store_true", help="leave the reference out")
    args = parser.parse_args()
    seeds = list(range(args.seeds))
    hindsight = not args.no_hindsight
    if args.table == "table1":
        for mode in ("paper", "drain"):
            body = table1(mode, seeds, args.workers, hindsight)
            print(body, flush=True)
            replace_section(f"table1_{mode}", body)
    elif args.table == "table2":
        body = table2(seeds, args.workers, hindsight)
        print(body)
        replace_section("table2", body)
    elif args.table == "table2_hindsight":
        body = table2_hindsight(seeds, args.workers)
        print(body)
        replace_section("table2_hindsight", body)
    elif args.table == "navigators":
        body = navigators(seeds, args.workers, hindsight)
        print(body)
        replace_section("navigators", body)
    else:
        body = transfer(seeds, args.workers)
        print(body)
        replace_section("transfer", body)
    return 0


if __name__ == "__main__":
    sys.exit(main())
