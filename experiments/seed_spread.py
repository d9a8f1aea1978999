"""The spread between training runs: one registry entry trained with several seeds.

Usage::

    python experiments/seed_spread.py C_astar_m10_plus --train-seeds 1 2 --jobs 2
    python experiments/seed_spread.py C_astar_m10_plus --train-seeds 1 2 --eval-only

Trains the entry's exact ``rtaw-train`` command with ``seed=K`` for each extra training
seed (into ``runs/seeds/<name>_s<K>``; seed 0 is the shipped policy), then evaluates every
run's best checkpoint beside MPDM, RBTS and lookahead on the evaluation seeds 0..N-1 of
the entry's own scenario, and prints each run's paired difference against each rule.
Per-seed TTDs go to ``docs/data/seed_spread_<name>.json``.
"""

from __future__ import annotations

import argparse
import json
import shutil
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

from rtaw_marl.config import compose, to_typed
from rtaw_marl.evaluation import evaluate
from rtaw_marl.evaluation.stats import paired_difference
from rtaw_marl.policies import make_baseline
from rtaw_marl.policies.network import load_policy
from rtaw_marl.policies.pretrained.registry import PRETRAINED, pretrained_path, train_command
from rtaw_marl.utils.atomic import atomic_write

ROOT = Path(__file__).resolve().parents[1]
RULES = ("mpdm", "rbts", "lookahead")


def train_seed(name: str, seed: int) -> Path:
    """Train ``name`` with ``seed``; returns the best checkpoint."""
    run_dir = ROOT / "runs" / "seeds" / f"{name}_s{seed}"
    shutil.rmtree(run_dir, ignore_errors=True)
    cmd = [*train_command(name, run_dir), f"seed={seed}"]
    run_dir.parent.mkdir(parents=True, exist_ok=True)
    with (run_dir.parent / f"{name}_s{seed}.log").open("w") as fh:
        subprocess.run(cmd, check=True, cwd=ROOT, stdout=fh, stderr=subprocess.STDOUT)
    return run_dir / "checkpoints" / "best.pt"


def evaluate_runs(name: str, checkpoints: dict[int, Path], seeds: list[int]) -> dict:
    """Per-seed TTDs of the rules and of each training run on the entry's scenario."""
    cfg = to_typed(compose("train", PRETRAINED[name]))
    sim = cfg.sim_spec().build()
    policies = {r: make_baseline(r, sim.navigator, sim.layout.scale) for r in RULES}
    policies.update({f"seed {k}": load_policy(path) for k, path in checkpoints.items()})
    return {label: res["ttd"] for label, res in evaluate(sim, policies, seeds).items()}


def report(ttd: dict[str, list[float]]) -> str:
    """A markdown table: each run's mean TTD and paired difference against each rule."""
    head = "| run | mean TTD | " + " | ".join(f"vs {r}" for r in RULES) + " |"
    lines = [head, "|" + "---|" * (2 + len(RULES))]
    for label, values in ttd.items():
        if label in RULES:
            continue
        cells = []
        for rule in RULES:
            d = paired_difference(ttd[rule], values)
            mark = "*" if d.significant else ""
            cells.append(f"{d.pct:+.1f}% [{d.pct_low:+.1f}, {d.pct_high:+.1f}]{mark}")
        mean = sum(values) / len(values)
        lines.append(f"| {label} | {mean:.0f} | " + " | ".join(cells) + " |")
    means = ", ".join(f"{r} {sum(ttd[r]) / len(ttd[r]):.0f}" for r in RULES)
    return "\n".join(lines) + f"\n\nRules' mean TTD: {means}."


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("name", help="a registry entry")
    parser.add_argument("--train-seeds", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--jobs", type=int, default=1, help="training runs at once")
    parser.add_argument("--seeds", type=int, default=20, help="evaluate on seeds 0..N-1")
    parser.add_argument("--eval-only", action="store_true", help="reuse trained runs")
    args = parser.parse_args()
    if args.eval_only:
        runs = {
            k: ROOT / "runs" / "seeds" / f"{args.name}_s{k}" / "checkpoints" / "best.pt"
            for k in args.train_seeds
        }
    else:
        with ThreadPoolExecutor(max_workers=args.jobs) as pool:
            paths = pool.map(lambda k: train_seed(args.name, k), args.train_seeds)
            runs = dict(zip(args.train_seeds, paths, strict=True))
    checkpoints = {0: pretrained_path(args.name), **runs}
    seeds = list(range(args.seeds))
    ttd = evaluate_runs(args.name, checkpoints, seeds)
    out = ROOT / "docs" / "data" / f"seed_spread_{args.name}.json"
    atomic_write(out, lambda fh: fh.write(json.dumps({"seeds": seeds, "ttd": ttd}).encode()))
    print(report(ttd))
    return 0


if __name__ == "__main__":
    sys.exit(main())
