"""Regenerate the results tables of docs/results.md, with paired 95% intervals.

Usage::

    python experiments/paper_tables.py table1      # Table I, paper and drain modes
    python experiments/paper_tables.py table2 --no-hindsight   # Table II: 5,000 tasks
    python experiments/paper_tables.py table2_hindsight --seeds 5   # its hindsight column
    python experiments/paper_tables.py transfer    # cross-layout transfer of the zoo
    python experiments/paper_tables.py navigators  # SIPP and CBS execution
    python experiments/paper_tables.py table1 --seeds 5 --workers 2   # quicker, 2 processes
    python experiments/paper_tables.py table1 --reuse   # rules from docs/data, learned anew

Every table is evaluated on the evaluation seeds 0-19 (``--seeds N``: 0..N-1); the
pretrained policies were trained and selected on other seeds. Each row evaluates MPDM,
RBTS, ``lookahead`` (H = 3), ``hungarian``, the ``hindsight`` reference (knows the
future; ``--no-hindsight`` leaves it out) and the zoo's learned policies ``RTAW`` (the
paper's network, registry entry ``X``) and ``RTAW+`` (entry ``X_plus``); one whose
checkpoint is missing or does not load is skipped with a warning and shown as ``-``.
``--reuse`` takes the rules' per-seed TTDs (hindsight included; rules are deterministic
given the seed) from docs/data/<name>.json when it holds the same seeds, and evaluates
only what is missing, normally RTAW and RTAW+. Each section shows:

* mean TTD per policy and the share of hindsight's gain over MPDM that lookahead, RTAW
  and RTAW+ capture;
* paired comparisons: RTAW+ against MPDM, RBTS, hungarian and lookahead, RTAW against
  MPDM and the strongest rule of the row (lowest mean TTD among RBTS, lookahead and
  hungarian): the difference in % of the baseline's mean, its 95% Student t-interval
  over seeds, ``*`` where it excludes 0;
* pooled lines: per-seed differences of every row (each in % of its row's baseline mean)
  with a t-interval over all row-seed pairs; the pooled hindsight share, a ratio of means:
  the mean over rows of ``1 - mean(policy) / mean(MPDM)`` over the same for hindsight
  (not a mean of per-row shares); RTAW+'s row wins; RTAW+ against the goals of +10%
  over MPDM and a 70% hindsight share (reported, not asserted).

The script replaces its section of docs/results.md (between ``<!-- BEGIN name -->`` and
``<!-- END name -->``) and writes the per-seed TTDs, with ``--reuse`` the union of the
reused and new ones, to docs/data/<name>.json (``{"seeds": [...], "rows": {row: {policy:
[ttd per seed]}}}``); ``transfer`` and ``table2_hindsight`` store none and reuse none.
"""

from __future__ import annotations

import argparse
import functools
import json
import sys
import time
from collections.abc import Iterator
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

import numpy as np

from rtaw_marl.errors import ConfigError
from rtaw_marl.evaluation import evaluate
from rtaw_marl.evaluation.stats import PairedDiff, hindsight_share, paired_difference
from rtaw_marl.policies import make_baseline
from rtaw_marl.policies.network import load_policy
from rtaw_marl.policies.pretrained.registry import pretrained_path
from rtaw_marl.sim.builder import SimSpec
from rtaw_marl.utils.atomic import atomic_write

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "docs" / "results.md"
DATA = ROOT / "docs" / "data"
#: Rule label -> make_baseline name; their TTDs depend on the seed only (``--reuse``).
BASELINES = {"MPDM": "mpdm", "RBTS": "rbts", "lookahead": "lookahead",
             "hungarian": "hungarian", "hindsight": "hindsight"}  # fmt: skip
#: Learned label -> suffix of its pretrained registry entry.
LEARNED = {"RTAW": "", "RTAW+": "_plus"}
ORDER = (*BASELINES, *LEARNED)
RULES = ("RBTS", "lookahead", "hungarian")  # candidates for the strongest rule of a row
STRONGEST = "the strongest rule"
SHARES = ("lookahead", *LEARNED)

#: Table I rows: label, layout spec, navigator, pretrained scenario per robot count.
ROWS = [
    ("Direct (open 60x60)", {"name": "open", "width": 60, "height": 60}, "direct",
     {10: "open60_direct_m10", 100: "open60_direct_m100"}),
    *[
        (f"A* layout {p}", {"name": "preset", "preset": p, "width": 60, "height": 60}, "astar",
         {10: f"{p}_astar_m10", 100: f"{p}_astar_m100"})
        for p in "ABCDE"
    ],
]  # fmt: skip

Ttd = dict[str, list[float]]


# --------------------------------------------------------------------------- evaluation
@functools.cache
def learned_entry(scenario: str, label: str) -> str | None:
    """Registry entry of ``label`` for ``scenario``; None, with a one-line warning on
    stderr, when its checkpoint is missing or does not load."""
    name = scenario + LEARNED[label]
    try:
        load_policy(pretrained_path(name), name=label)
    except ConfigError as err:
        print(f"warning: {label} skipped: {' '.join(str(err).split())}", file=sys.stderr)
        return None
    return name


def scenario_of(job: dict[str, Any], label: str) -> str:
    """The pretrained scenario of ``label`` in ``job``: ``job["pretrained"]`` is one
    scenario for every learned label or a ``{label: scenario}`` mapping."""
    pretrained = job["pretrained"]
    return pretrained[label] if isinstance(pretrained, dict) else pretrained


def wanted(job: dict[str, Any]) -> list[str]:
    """Labels a job evaluates: every rule (hindsight unless ``job["hindsight"]`` is
    false) and, with ``pretrained``, the learned policies that load; ``only`` keeps a
    subset of them."""
    labels = [b for b in BASELINES if b != "hindsight" or job.get("hindsight", True)]
    if job.get("pretrained"):
        labels += [p for p in LEARNED if learned_entry(scenario_of(job, p), p)]
    return [p for p in labels if p in job.get("only", labels)]


def evaluate_setting(job: dict[str, Any]) -> dict[str, Any]:
    """Evaluate ``job["policies"]`` (default :func:`wanted`) on one setting; returns
    per-seed TTDs and seconds per episode."""
    sim = SimSpec.of(job["env"], job["layout"], job["navigator"], job["tasks"]).build()
    policies: dict[str, Any] = {}
    for label in job["policies"] if "policies" in job else wanted(job):
        if label in BASELINES:
            policies[label] = make_baseline(BASELINES[label], sim.navigator, sim.layout.scale)
        else:
            path = pretrained_path(scenario_of(job, label) + LEARNED[label])
            policies[label] = load_policy(path, name=label)
    res = evaluate(sim, policies, job["seeds"]) if policies else {}
    return {
        "key": job["key"],
        "ttd": {k: v["ttd"] for k, v in res.items()},
        "seconds": {k: float(np.mean(v["wall_time_s"])) for k, v in res.items()},
    }


def load_saved(name: str, seeds: list[int]) -> dict[str, Ttd]:
    """The rows of docs/data/<name>.json when it holds exactly ``seeds``, else {}."""
    path = DATA / f"{name}.json"
    payload = json.loads(path.read_text()) if path.is_file() else {}
    if payload.get("seeds") != seeds:
        print(f"warning: --reuse: {path} is missing or has other seeds", file=sys.stderr)
        return {}
    return payload["rows"]


def run_all(
    jobs: list[dict[str, Any]], workers: int, saved: dict[str, Ttd] | None = None
) -> dict[Any, dict[str, Any]]:
    """Every job keyed by ``job["key"]``, on ``workers`` processes; rule TTDs found in
    ``saved`` (rows by ``str(key)``) are reused and only the missing policies run."""
    out, todo = {}, []
    for job in jobs:
        kept = {k: v for k, v in (saved or {}).get(str(job["key"]), {}).items() if k in BASELINES}
        out[job["key"]] = {"key": job["key"], "ttd": kept, "seconds": {}}
        missing = [p for p in wanted(job) if p not in kept]
        if missing:
            todo.append({**job, "policies": tuple(missing)})
        if kept:
            print(f"reused {job['key']}: {', '.join(kept)}", file=sys.stderr, flush=True)
    for result in evaluated(todo, workers):
        row = out[result["key"]]
        ttd = {**row["ttd"], **result["ttd"]}
        row["ttd"] = {p: ttd[p] for p in ORDER if p in ttd}
        row["seconds"] = result["seconds"]
        print(f"done {result['key']}", file=sys.stderr, flush=True)
    return out


def evaluated(jobs: list[dict[str, Any]], workers: int) -> Iterator[dict[str, Any]]:
    """:func:`evaluate_setting` of each job, in order; in this process for one worker."""
    if workers <= 1 or len(jobs) <= 1:
        yield from map(evaluate_setting, jobs)
        return
    with ProcessPoolExecutor(max_workers=workers) as pool:
        yield from pool.map(evaluate_setting, jobs)


# --------------------------------------------------------------------------- cells
def vs(base: list[float], other: list[float]) -> str:
    """``+3.1% [+1.2, +5.0]*``: ``other``'s TTD below ``base``'s, paired over seeds."""
    d = paired_difference(base, other)
    if d.pct_low is None:
        return f"{d.pct:+.1f}%"
    mark = "*" if d.significant else ""
    return f"{d.pct:+.1f}% [{d.pct_low:+.1f}, {d.pct_high:+.1f}]{mark}"


def share(ttd: Ttd, name: str) -> str:
    if not {"MPDM", "hindsight", name} <= ttd.keys():
        return "-"
    s = hindsight_share(ttd["MPDM"], ttd[name], ttd["hindsight"])
    return "-" if s is None else f"{100 * s.share:.0f}%"


def strongest_rule(ttd: Ttd) -> str:
    return min((r for r in RULES if r in ttd), key=lambda r: float(np.mean(ttd[r])), default="-")


def baseline(ttd: Ttd, base: str) -> str:
    return strongest_rule(ttd) if base == STRONGEST else base


def compare(ttd: Ttd, base: str, other: str) -> str:
    """``vs`` of ``other`` against ``base`` (or :data:`STRONGEST`, then named), or ``-``."""
    rule = baseline(ttd, base)
    if rule not in ttd or other not in ttd:
        return "-"
    cell = vs(ttd[rule], ttd[other])
    return f"{rule}: {cell}" if base == STRONGEST else cell


def pooled_diff(rows: list[Ttd], base: str, other: str) -> PairedDiff | None:
    """Per-seed differences of every row having both, each in % of its row's baseline mean."""
    pairs = [(t[b], t[other]) for t in rows if (b := baseline(t, base)) in t and other in t]
    if not pairs:
        return None
    diffs = np.concatenate([100 * (np.asarray(b) - np.asarray(o)) / np.mean(b) for b, o in pairs])
    return paired_difference(diffs, np.zeros_like(diffs))  # the interval of their mean


def pooled(rows: list[Ttd], base: str, other: str) -> str:
    d = pooled_diff(rows, base, other)
    if d is None:
        return "-"
    mark = "*" if d.significant else ""
    ci = "" if d.low is None else f" [{d.low:+.1f}, {d.high:+.1f}]{mark}"
    return f"{d.mean:+.1f}%{ci} (n={d.n})"


def pooled_share(rows: list[Ttd], name: str) -> float | None:
    """Mean over rows of ``name``'s relative gain over MPDM / the same of hindsight."""
    rows = [t for t in rows if {"MPDM", "hindsight", name} <= t.keys()]
    if not rows:
        return None

    def gain(t: Ttd, p: str) -> float:
        return 1.0 - float(np.mean(t[p]) / np.mean(t["MPDM"]))

    ref = np.mean([gain(t, "hindsight") for t in rows])
    return None if ref <= 0 else float(np.mean([gain(t, name) for t in rows]) / ref)


def wins(rows: list[Ttd], base: str, other: str = "RTAW+") -> str:
    diffs = [paired_difference(t[base], t[other]) for t in rows if base in t and other in t]
    better = sum(d.mean > 0 for d in diffs)
    sig = sum(d.mean > 0 and d.significant for d in diffs)
    worse = sum(d.mean < 0 and d.significant for d in diffs)
    return (f"- {other} beats {base} on {better} of {len(diffs)} rows (significantly on "
            f"{sig}; significantly worse on {worse})")  # fmt: skip


def markdown(head: list[str], rows: list[list[str]]) -> str:
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    return "\n".join([*lines, *("| " + " | ".join(r) + " |" for r in rows)])


def percent(value: float | None) -> str:
    return "-" if value is None else f"{100 * value:.0f}%"


def mean_cell(ttd: Ttd, name: str) -> str:
    return f"{np.mean(ttd[name]):.0f}" if name in ttd else "-"


def shares(ttd: Ttd) -> str:
    return " / ".join(share(ttd, p) for p in SHARES)


# --------------------------------------------------------------------------- sections
#: The paired comparisons of each row, (policy, baseline).
COMPARISONS = [("RTAW+", "MPDM"), ("RTAW+", "RBTS"), ("RTAW+", "hungarian"),
               ("RTAW+", "lookahead"), ("RTAW", "MPDM"), ("RTAW", STRONGEST)]  # fmt: skip
#: The pooled lines of a section, (policy, baseline).
POOLED = [*COMPARISONS[:4], ("RTAW+", STRONGEST), *COMPARISONS[4:], ("lookahead", "MPDM")]


def section(results: dict[Any, dict[str, Any]], keys: list[Any]) -> str:
    """Mean TTDs and hindsight shares, paired comparisons, then the pooled lines."""
    rows = {str(k): results[k]["ttd"] for k in keys}
    means = markdown(
        ["setting", *ORDER, "hindsight share: " + " / ".join(SHARES)],
        [[k, *(mean_cell(t, p) for p in ORDER), shares(t)] for k, t in rows.items()],
    )
    comparisons = markdown(
        ["setting", *(f"{o} vs {b}" for o, b in COMPARISONS)],
        [[k, *(compare(t, b, o) for o, b in COMPARISONS)] for k, t in rows.items()],
    )
    return f"{means}\n\n{comparisons}\n\n" + "\n".join(summary(list(rows.values())))


def summary(rows: list[Ttd]) -> list[str]:
    """Pooled comparisons and shares, RTAW+'s wins per row and its goals."""
    lines = [f"- {o} vs {b}, pooled: {pooled(rows, b, o)}" for o, b in POOLED]
    lines.append(share_line(rows))
    lines += [wins(rows, b) for b in ("lookahead", "MPDM", "RBTS")]
    d, s = pooled_diff(rows, "MPDM", "RTAW+"), pooled_share(rows, "RTAW+")
    gain = "-" if d is None else f"{'met' if d.mean >= 10 else 'not met'} ({d.mean:+.1f}%)"
    part = "-" if s is None else f"{'met' if s >= 0.7 else 'not met'} ({percent(s)})"
    lines.append(f"- RTAW+ goals (reported, not asserted): >= +10% vs MPDM pooled: {gain}; "
                 f">= 70% hindsight share pooled: {part}")  # fmt: skip
    return lines


def share_line(rows: list[Ttd]) -> str:
    values = " / ".join(percent(pooled_share(rows, p)) for p in SHARES)
    return f"- hindsight share, pooled ({' / '.join(SHARES)}): {values}"


def run_table(name: str, jobs: list[dict[str, Any]], seeds: list[int], workers: int,
              reuse: bool) -> dict[Any, dict[str, Any]]:  # fmt: skip
    """Run (reusing stored rule TTDs with ``reuse``) and store docs/data/<name>.json."""
    results = run_all(jobs, workers, load_saved(name, seeds) if reuse else None)
    save(name, results, seeds)
    return results


# --------------------------------------------------------------------------- tables
def table1(mode: str, seeds: list[int], workers: int, hindsight: bool, reuse: bool) -> str:
    jobs = []
    for label, layout, nav, pretrained in ROWS:
        for m in (10, 100):
            env = {"num_robots": m, "num_tasks": 500, "queue_len": 10, "episode_mode": mode}
            jobs.append({"key": f"{label}, M={m}", "env": env, "layout": layout,
                         "navigator": nav, "tasks": "designated",
                         "pretrained": f"{pretrained[m]}_long",
                         "seeds": seeds, "hindsight": hindsight})  # fmt: skip
    results = run_table(f"table1_{mode}", jobs, seeds, workers, reuse)
    return section(results, [job["key"] for job in jobs])


#: Table II settings: label, layout, navigator, pretrained scenario per learned label (the
#: paper's network trained with 100 robots; RTAW+ continued with 500, a curriculum).
TABLE2_SETTINGS = [
    ("Direct, open 300x300", {"name": "open", "width": 300, "height": 300}, "direct",
     {"RTAW": "open300_direct_m100_random", "RTAW+": "open300_direct_m500_random"}),
    ("A*, layout C 256x256", {"name": "preset", "preset": "C", "width": 256, "height": 256},
     "astar", {"RTAW": "C256_astar_m100_random", "RTAW+": "C256_astar_m500_random"}),
]  # fmt: skip


def table2_jobs(seeds: list[int], **extra: Any) -> list[dict[str, Any]]:
    """Table II's settings; random tasks over the whole grid (the designated centres of
    the 60x60 setting would leave most of a 256x256 or 300x300 grid unused)."""
    jobs = []
    for m in (500, 1000):
        for label, layout, nav, pretrained in TABLE2_SETTINGS:
            env = {"num_robots": m, "num_tasks": 5000, "queue_len": 10, "episode_mode": "paper"}
            jobs.append({"key": f"M={m}, {label}", "env": env, "layout": layout,
                         "navigator": nav, "tasks": "random", "pretrained": pretrained,
                         "seeds": seeds, **extra})  # fmt: skip
    return jobs


def table2(seeds: list[int], workers: int, hindsight: bool, reuse: bool) -> str:
    jobs = table2_jobs(seeds, hindsight=hindsight)
    results = run_table("table2", jobs, seeds, workers, reuse)
    wall = ["", "Seconds per episode (mean over seeds, policies evaluated in this run):", ""]
    for job in jobs:
        secs = results[job["key"]]["seconds"]
        wall.append(f"- {job['key']}: " + ", ".join(f"{k} {v:.1f}" for k, v in secs.items()))
    return section(results, [job["key"] for job in jobs]) + "\n" + "\n".join(wall)


def table2_hindsight(seeds: list[int], workers: int) -> str:
    """The hindsight reference on Table II's first seeds (about a minute per episode at
    1,000 robots), against the policies' TTDs of ``docs/data/table2.json``."""
    saved = json.loads((DATA / "table2.json").read_text())["rows"]
    results = run_all(table2_jobs(seeds, only=("hindsight",)), workers)
    n, cols = len(seeds), ("MPDM", "lookahead", *LEARNED, "hindsight")
    head = ["setting", "seeds", *cols, "hindsight share: " + " / ".join(SHARES)]
    rows, ttds = [], []
    for key, res in results.items():
        ttd = {k: v[:n] for k, v in saved[key].items() if k != "hindsight"}
        ttd["hindsight"] = res["ttd"]["hindsight"]
        ttds.append(ttd)
        rows.append([key, f"0-{n - 1}", *(mean_cell(ttd, p) for p in cols), shares(ttd)])
    return markdown(head, rows) + "\n\n" + share_line(ttds)


def transfer(seeds: list[int], workers: int) -> str:
    """Each layout's learned policies on every layout (M = 10, A*, drain), vs MPDM."""
    presets, jobs = "ABCDE", []
    for p in presets:
        base = {"env": {"num_robots": 10, "num_tasks": 500}, "navigator": "astar",
                "layout": {"name": "preset", "preset": p, "width": 60, "height": 60},
                "tasks": "designated", "seeds": seeds}  # fmt: skip
        jobs.append({**base, "key": ("MPDM", p), "only": ("MPDM",)})
        jobs += [{**base, "key": (t, p), "only": tuple(LEARNED),
                  "pretrained": f"{t}_astar_m10"} for t in presets]  # fmt: skip
    results = run_all(jobs, workers)
    ttd = {(t, p): {**results[("MPDM", p)]["ttd"], **results[(t, p)]["ttd"]}
           for t in presets for p in presets}  # fmt: skip
    parts = []
    for label in LEARNED:
        head = [f"{label}: trained on \\ evaluated on", *presets]
        rows = [[t, *(compare(ttd[t, p], "MPDM", label) for p in presets)] for t in presets]
        own = [v for (t, p), v in ttd.items() if t == p]
        other = [v for (t, p), v in ttd.items() if t != p]
        parts.append(markdown(head, rows) + f"\n\n- {label} vs MPDM, pooled: own layout "
                     f"{pooled(own, 'MPDM', label)}; other layouts "
                     f"{pooled(other, 'MPDM', label)}")  # fmt: skip
    return "\n\n".join(parts)


#: The pooled lines per navigator, (policy, baseline).
NAV_POOLED = [("RTAW+", "MPDM"), ("RTAW+", "RBTS"), ("RTAW+", "lookahead"),
              ("RTAW", "MPDM"), ("RTAW", "RBTS"), ("lookahead", "MPDM")]  # fmt: skip


def navigators(seeds: list[int], workers: int, hindsight: bool, reuse: bool) -> str:
    """10 robots, 50 designated tasks on layouts A-E, with A*, SIPP and CBS execution."""
    env = {"num_robots": 10, "num_tasks": 50, "queue_len": 10, "noise_mean": 0.0, "noise_var": 0.0}
    navs, jobs = ("astar", "sipp", "cbs"), []
    for nav in navs:
        for p in "ABCDE":
            layout = {"name": "preset", "preset": p, "width": 60, "height": 60}
            jobs.append({"key": f"{p}, {nav}", "env": env, "layout": layout, "navigator": nav,
                         "tasks": "designated", "pretrained": f"{p}_astar_m10",
                         "seeds": seeds, "hindsight": hindsight})  # fmt: skip
    results = run_table("navigators", jobs, seeds, workers, reuse)
    lines = []
    for nav in navs:
        rows = [results[f"{p}, {nav}"]["ttd"] for p in "ABCDE"]
        parts = [f"{o} vs {b} {pooled(rows, b, o)}" for o, b in NAV_POOLED]
        lines.append(f"- {nav}, pooled over A-E: " + "; ".join(parts))
    return section(results, [job["key"] for job in jobs]) + "\n" + "\n".join(lines)


# --------------------------------------------------------------------------- files
def save(name: str, results: dict[Any, dict[str, Any]], seeds: list[int]) -> None:
    DATA.mkdir(parents=True, exist_ok=True)
    payload = {"seeds": seeds, "rows": {str(k): v["ttd"] for k, v in results.items()}}
    text = json.dumps(payload, indent=1) + "\n"
    atomic_write(DATA / f"{name}.json", lambda fh: fh.write(text.encode()))


def replace_section(name: str, body: str) -> None:
    """Replace the text between the section's markers in docs/results.md."""
    text = RESULTS.read_text()
    begin, end = f"<!-- BEGIN {name} -->", f"<!-- END {name} -->"
    if begin not in text or end not in text:
        raise SystemExit(f"docs/results.md has no {begin} ... {end} markers")
    head, rest = text.split(begin, 1)
    _, tail = rest.split(end, 1)
    stamp = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())
    page = f"{head}{begin}\n_Generated {stamp}._\n\n{body}\n{end}{tail}"
    atomic_write(RESULTS, lambda fh: fh.write(page.encode()))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument(
        "table", choices=["table1", "table2", "table2_hindsight", "transfer", "navigators"]
    )
    parser.add_argument("--seeds", type=int, default=20, help="evaluate on seeds 0..N-1")
    parser.add_argument("--workers", type=int, default=1, help="evaluation processes")
    parser.add_argument("--no-hindsight", action="store_true", help="leave the reference out")
    parser.add_argument(
        "--reuse", action="store_true", help="take the rules' TTDs from docs/data/<name>.json"
    )
    args = parser.parse_args(argv)
    seeds, workers, hindsight = list(range(args.seeds)), args.workers, not args.no_hindsight
    if args.reuse and args.table in ("transfer", "table2_hindsight"):
        print(f"warning: --reuse has no effect on {args.table}", file=sys.stderr)
    sections = {
        "table1_paper": lambda: table1("paper", seeds, workers, hindsight, args.reuse),
        "table1_drain": lambda: table1("drain", seeds, workers, hindsight, args.reuse),
        "table2": lambda: table2(seeds, workers, hindsight, args.reuse),
        "table2_hindsight": lambda: table2_hindsight(seeds, workers),
        "transfer": lambda: transfer(seeds, workers),
        "navigators": lambda: navigators(seeds, workers, hindsight, args.reuse),
    }
    for name in ("table1_paper", "table1_drain") if args.table == "table1" else (args.table,):
        body = sections[name]()
        print(body, flush=True)
        replace_section(name, body)
    return 0


if __name__ == "__main__":
    sys.exit(main())
