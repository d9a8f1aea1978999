"""Does a longer budget pay? 100-robot Table I policies continued to more PPO frames.

Usage::

    python experiments/longer_budget.py E_astar_m100_plus open60_direct_m100_plus

For each entry, takes the best checkpoint of ``runs/longer_<entry>`` (the entry's run
continued with ``resume=<its last.pt> frames=<more>``: docs/training.md), evaluates it on
its Table I row (seeds 0-19, ``paper`` and ``drain`` modes), and pairs it per seed with
the shipped policy and the rules stored in ``docs/data/table1_<mode>.json``. Prints one
markdown row per entry and mode; per-seed TTDs go to ``docs/data/longer/<entry>.json``.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from paper_tables import ROWS

from rtaw_marl.evaluation import evaluate
from rtaw_marl.evaluation.stats import paired_difference
from rtaw_marl.models.checkpoint import load_checkpoint
from rtaw_marl.policies.network import load_policy
from rtaw_marl.sim.builder import SimSpec
from rtaw_marl.utils.atomic import atomic_write

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "docs" / "data"
SEEDS = list(range(20))


def row_of(entry: str) -> tuple[str, dict, str]:
    """Table I row key, layout and navigator of a 100-robot RTAW+ entry."""
    for label, layout, nav, pretrained in ROWS:
        if f"{pretrained[100]}_plus" == entry:
            return f"{label}, M=100", layout, nav
    raise SystemExit(f"error: {entry} is not a 100-robot RTAW+ entry of Table I")


def cell(base: list[float], ttd: list[float]) -> str:
    d = paired_difference(base, ttd)
    return f"{d.pct:+.1f}% [{d.pct_low:+.1f}, {d.pct_high:+.1f}]{'*' if d.significant else ''}"


def share(rows: dict[str, list[float]], ttd: list[float]) -> float:
    mpdm, hindsight = sum(rows["MPDM"]), sum(rows["hindsight"])
    return 100 * (mpdm - sum(ttd)) / (mpdm - hindsight)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("entries", nargs="+", help="100-robot RTAW+ registry entries")
    args = parser.parse_args()
    print("| row | frames | mode | vs shipped RTAW+ | vs lookahead (shipped -> longer) "
          "| hindsight share (shipped -> longer) |")  # fmt: skip
    print("|---|---|---|---|---|---|")
    for entry in args.entries:
        key, layout, nav = row_of(entry)
        best = ROOT / "runs" / f"longer_{entry}" / "checkpoints" / "best.pt"
        frames = load_checkpoint(best)["config"]["frames"]
        out = {"checkpoint": str(best.relative_to(ROOT)), "frames": frames, "seeds": SEEDS}
        for mode in ("paper", "drain"):
            rows = json.loads((DATA / f"table1_{mode}.json").read_text())["rows"][key]
            env = {"num_robots": 100, "num_tasks": 500, "queue_len": 10, "episode_mode": mode}
            sim = SimSpec.of(env, layout, nav, "designated").build()
            ttd = evaluate(sim, {"longer": load_policy(best)}, SEEDS)["longer"]["ttd"]
            out[mode] = ttd
            shipped = paired_difference(rows["lookahead"], rows["RTAW+"]).pct
            shares = f"{share(rows, rows['RTAW+']):.0f}% -> {share(rows, ttd):.0f}%"
            line = (
                f"| {key} | {frames:,} | {mode} | {cell(rows['RTAW+'], ttd)} | "
                f"{shipped:+.1f}% -> {cell(rows['lookahead'], ttd)} | {shares} |"
            )
            print(line, flush=True)
        text = json.dumps(out) + "\n"
        atomic_write(DATA / "longer" / f"{entry}.json", lambda fh, t=text: fh.write(t.encode()))
    return 0


if __name__ == "__main__":
    sys.exit(main())
