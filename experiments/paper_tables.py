"""Regenerate the results tables of docs/results.md.

Usage::

    python experiments/paper_tables.py table1    # Table I: 500 tasks, M = 10/100, Direct, A-E
    python experiments/paper_tables.py table2    # Table II: 5,000 tasks, M = 500/1000
    python experiments/paper_tables.py transfer  # cross-layout transfer of pretrained policies
    python experiments/paper_tables.py navigators  # SIPP and CBS (the paper's transfer table)
    python experiments/paper_tables.py navigators --seeds 20  # the same on seeds 0-19

Each command evaluates on seeds 0-4 (the pretrained policies were trained and selected on
other seeds), prints a markdown table, and replaces its section of docs/results.md
(between ``<!-- BEGIN name -->`` and ``<!-- END name -->``) together with a PNG in
docs/img/.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

from rtaw_marl.evaluation import evaluate
from rtaw_marl.evaluation.lower_bound import ttd_lower_bound
from rtaw_marl.policies import make_baseline
from rtaw_marl.policies.network import load_policy
from rtaw_marl.policies.pretrained.registry import pretrained_path
from rtaw_marl.sim.builder import SimSpec

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "docs" / "results.md"
IMG = ROOT / "docs" / "img"
SEEDS = [0, 1, 2, 3, 4]

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

#: The paper's Table I (MPDM, RBTS, RTAW means), by row label prefix and M.
PAPER_TABLE1 = {
    ("Direct", 10): (8312, 8376, 7924), ("Direct", 100): (13089, 13322, 12298),
    ("A* layout A", 10): (5662, 6194, 5165), ("A* layout A", 100): (7429, 7882, 7032),
    ("A* layout B", 10): (5591, 6098, 4989), ("A* layout B", 100): (7885, 8288, 7387),
    ("A* layout C", 10): (6205, 6503, 5861), ("A* layout C", 100): (7210, 7915, 6954),
    ("A* layout D", 10): (5920, 6675, 5719), ("A* layout D", 100): (7764, 8182, 7101),
    ("A* layout E", 10): (5536, 5916, 5281), ("A* layout E", 100): (7791, 8126, 7453),
}  # fmt: skip


def _policies(sim, pretrained: str) -> dict:
    return {
        "MPDM": make_baseline("mpdm", sim.navigator, sim.layout.scale),
        "RBTS": make_baseline("rbts", sim.navigator, sim.layout.scale),
        "RTAW": load_policy(pretrained_path(pretrained), name="RTAW"),
    }


def _ms(values) -> str:
    arr = np.asarray(values, dtype=float)
    return f"{arr.mean():.0f} ± {arr.std():.0f}"


def _imp(base, other) -> str:
    """Mean ± std over seeds of the per-seed percent improvement of ``other`` over ``base``."""
    imp = 100 * (np.asarray(base) - np.asarray(other)) / np.asarray(base)
    return f"{imp.mean():+.1f} ± {imp.std():.1f}"


def table1(mode: str) -> tuple[str, dict]:
    """Table I in ``paper`` or ``drain`` episode mode."""
    header = "| row | M | MPDM | RBTS | RTAW | RTAW vs MPDM (%) | RTAW vs RBTS (%) |"
    header += " paper MPDM / RBTS / RTAW |" if mode == "paper" else " lower bound | RTAW gap (%) |"
    lines = [header, "|" + "---|" * (header.count("|") - 1)]
    data = {}
    for label, layout, nav, pretrained in ROWS:
        for m in (10, 100):
            env = {"num_robots": m, "num_tasks": 500, "queue_len": 10, "episode_mode": mode}
            sim = SimSpec.of(env, layout, nav, "designated").build()
            res = evaluate(sim, _policies(sim, pretrained[m]), SEEDS)
            ttd = {k: v["ttd"] for k, v in res.items()}
            data[(label, m)] = ttd
            row = [label, str(m), _ms(ttd["MPDM"]), _ms(ttd["RBTS"]), _ms(ttd["RTAW"]),
                   _imp(ttd["MPDM"], ttd["RTAW"]), _imp(ttd["RBTS"], ttd["RTAW"])]  # fmt: skip
            if mode == "paper":
                paper = PAPER_TABLE1[(label.split(" (")[0], m)]
                row.append(" / ".join(str(v) for v in paper))
            else:
                bound = [ttd_lower_bound(sim, s) for s in SEEDS]
                gap = 100 * (np.asarray(ttd["RTAW"]) - bound) / np.asarray(bound)
                row += [_ms(bound), f"{gap.mean():.0f}"]
            lines.append("| " + " | ".join(row) + " |")
            print(lines[-1], flush=True)
    return "\n".join(lines), data


def table2() -> str:
    """Scalability: 5,000 random tasks, M = 500 and 1000; wall time per episode per policy."""
    rows = [
        ("Direct, open 300x300", {"name": "open", "width": 300, "height": 300}, "direct",
         "open300_direct_m100_random"),
        ("A*, layout C 256x256", {"name": "preset", "preset": "C", "width": 256, "height": 256},
         "astar", "C256_astar_m100_random"),
    ]  # fmt: skip
    header = (
        "| M | setting | MPDM | RBTS | RTAW | RTAW vs MPDM (%) | RTAW vs RBTS (%) | "
        "s/episode MPDM / RBTS / RTAW |"
    )
    lines = [header, "|" + "---|" * (header.count("|") - 1)]
    for m in (500, 1000):
        for label, layout, nav, pretrained in rows:
            env = {"num_robots": m, "num_tasks": 5000, "queue_len": 10, "episode_mode": "paper"}
            # Random tasks spread over the whole grid: the designated centres of the
            # 60x60 setting would leave most of a 256x256 or 300x300 grid unused.
            sim = SimSpec.of(env, layout, nav, "random").build()
            res = evaluate(sim, _policies(sim, pretrained), SEEDS)
            ttd = {k: v["ttd"] for k, v in res.items()}
            wall = " / ".join(f"{np.mean(res[k]['wall_time_s']):.1f}" for k in res)
            lines.append(
                f"| {m} | {label} | {_ms(ttd['MPDM'])} | {_ms(ttd['RBTS'])} | {_ms(ttd['RTAW'])} "
                f"| {_imp(ttd['MPDM'], ttd['RTAW'])} | {_imp(ttd['RBTS'], ttd['RTAW'])} | {wall} |"
            )
            print(lines[-1], flush=True)
    return "\n".join(lines)


def transfer() -> str:
    """Each layout's pretrained policy evaluated on every layout (M = 10, A*, drain)."""
    presets = "ABCDE"
    header = "| trained on \\ evaluated on | " + " | ".join(presets) + " |"
    lines = [header, "|" + "---|" * (len(presets) + 1)]
    mpdm = {}
    for p in presets:
        sim = SimSpec.of({"num_robots": 10, "num_tasks": 500}, {"name": "preset", "preset": p},
                        "astar", "designated").build()  # fmt: skip
        mpdm[p] = evaluate(sim, {"m": make_baseline("mpdm")}, SEEDS)["m"]["ttd"]
    for trained in presets:
        cells = []
        for p in presets:
            sim = SimSpec.of({"num_robots": 10, "num_tasks": 500}, {"name": "preset", "preset": p},
                            "astar", "designated").build()  # fmt: skip
            policy = load_policy(pretrained_path(f"{trained}_astar_m10"))
            ttd = evaluate(sim, {"r": policy}, SEEDS)["r"]["ttd"]
            cells.append(_imp(mpdm[p], ttd))
        lines.append(f"| {trained} | " + " | ".join(cells) + " |")
        print(lines[-1], flush=True)
    return "\n".join(lines)


#: The paper's SIPP/CBS table (MPDM, RBTS, RTAW means; 10 robots, 50 tasks).
PAPER_NAVIGATORS = {
    ("sipp", "A"): (692, 725, 645), ("sipp", "B"): (616, 636, 566), ("sipp", "C"): (684, 707, 626),
    ("sipp", "D"): (710, 706, 642), ("sipp", "E"): (643, 689, 595),
    ("cbs", "A"): (644, 696, 615), ("cbs", "B"): (680, 675, 619), ("cbs", "C"): (655, 670, 625),
    ("cbs", "D"): (766, 817, 738), ("cbs", "E"): (618, 671, 591),
}  # fmt: skip


def navigators(seeds: list[int]) -> str:
    """10 robots, 50 designated tasks on layouts A-E, executed by SIPP and CBS (and A*).

    RTAW is each layout's A*-trained policy; no completion noise (the collision-aware
    navigators time tasks in whole seconds), drain mode: all 50 tasks are delivered.
    The last rows pool every layout's per-seed improvements (mean ± standard error).
    """
    header = (
        "| layout | navigator | MPDM | RBTS | RTAW | RTAW vs MPDM (%) | RTAW vs RBTS (%) | "
        "paper MPDM / RBTS / RTAW |"
    )
    lines = [header, "|" + "---|" * (header.count("|") - 1)]
    env = {"num_robots": 10, "num_tasks": 50, "queue_len": 10, "noise_mean": 0.0, "noise_var": 0.0}
    pooled: dict[str, dict[str, list[float]]] = {}
    for p in "ABCDE":
        for nav in ("astar", "sipp", "cbs"):
            layout = {"name": "preset", "preset": p, "width": 60, "height": 60}
            sim = SimSpec.of(env, layout, nav, "designated").build()
            res = evaluate(sim, _policies(sim, f"{p}_astar_m10"), seeds)
            ttd = {k: np.asarray(v["ttd"]) for k, v in res.items()}
            for base in ("MPDM", "RBTS"):
                imp = 100 * (ttd[base] - ttd["RTAW"]) / ttd[base]
                pooled.setdefault(nav, {}).setdefault(base, []).extend(imp.tolist())
            paper = PAPER_NAVIGATORS.get((nav, p))
            lines.append(
                f"| {p} | {nav} | {_ms(ttd['MPDM'])} | {_ms(ttd['RBTS'])} | {_ms(ttd['RTAW'])} "
                f"| {_imp(ttd['MPDM'], ttd['RTAW'])} | {_imp(ttd['RBTS'], ttd['RTAW'])} "
                f"| {' / '.join(map(str, paper)) if paper else '-'} |"
            )
            print(lines[-1], flush=True)
    for nav, imps in pooled.items():
        cells = []
        for base in ("MPDM", "RBTS"):
            arr = np.asarray(imps[base])
            cells.append(f"{arr.mean():+.1f} ± {arr.std(ddof=1) / np.sqrt(len(arr)):.1f} (SE)")
        lines.append(f"| all | {nav} | | | | {cells[0]} | {cells[1]} | |")
    return "\n".join(lines)


def plot_table1(data: dict, path: Path) -> None:
    """Bar chart: mean TTD per policy per row with std error bars."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    keys = list(data)
    x = np.arange(len(keys))
    fig, ax = plt.subplots(figsize=(11, 4), dpi=110)
    for i, name in enumerate(("MPDM", "RBTS", "RTAW")):
        means = [np.mean(data[k][name]) for k in keys]
        stds = [np.std(data[k][name]) for k in keys]
        ax.bar(x + (i - 1) * 0.27, means, 0.27, yerr=stds, capsize=2, label=name)
    labels = [k[0].replace("A* layout ", "").split(" (")[0] for k in keys]
    ax.set_xticks(x, [f"{lab}\nM={k[1]}" for lab, k in zip(labels, keys, strict=True)], fontsize=8)
    ax.set_ylabel("TTD (s), 500 tasks, seeds 0-4")
    ax.legend()
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path)
    plt.close(fig)


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
    parser.add_argument("table", choices=["table1", "table2", "transfer", "navigators"])
    parser.add_argument(
        "--seeds", type=int, default=len(SEEDS), help="navigators: evaluate on seeds 0..N-1"
    )
    args = parser.parse_args()
    if args.table == "table1":
        paper, data = table1("paper")
        replace_section("table1_paper", paper)
        plot_table1(data, IMG / "table1_ttd.png")
        drain, _ = table1("drain")
        replace_section("table1_drain", drain)
    elif args.table == "table2":
        replace_section("table2", table2())
    elif args.table == "navigators":
        seeds = list(range(args.seeds))
        name = "navigators" if seeds == SEEDS else f"navigators_{len(seeds)}"
        replace_section(name, navigators(seeds))
    else:
        replace_section("transfer", transfer())
    return 0


if __name__ == "__main__":
    sys.exit(main())
