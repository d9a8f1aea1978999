"""Does a training aid pay? One zoo entry retrained with extra overrides, several
training seeds, against the same entry's runs without them.

Usage::

    python -m benchmarks.scripts.seed_spread C_astar_m10_plus --train-seeds 1 2   # the reference
    python -m benchmarks.scripts.ablation C_astar_m10_plus model.critic_fleet=false --train-seeds 0 1
    # A curriculum: the first 204,800 PPO frames (and the warm start) with a queue of 5.
    python -m benchmarks.scripts.ablation C_astar_m10_plus --first sim.queue_len=5 --first-frames 204800

Trains the entry's recipe plus the overrides with ``seed=K`` for each training seed
(:func:`benchmarks.variants.ablation_commands`, into
``runs/ablation/<name>_<tag>_s<K>``; with ``--first``, a first stage with those
overrides for ``--first-frames`` PPO frames, then the run continues it on the entry's
own scenario to the entry's own budget). Then it evaluates each run's best checkpoint
on the evaluation seeds stored by ``seed_spread.py`` (its entry's own scenario), and
prints each run against the rules and, per evaluation seed, the mean of the ablated runs
against the mean of the reference runs (seed 0 is the shipped policy): a paired
difference over evaluation seeds, whose interval does not include the spread between
training runs, so read it beside the per-run lines. Per-seed TTDs go to
``benchmarks/data/ablation_<name>_<tag>.json``.
"""

from __future__ import annotations

import argparse
import json
import shutil
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np

from benchmarks.tables import vs
from benchmarks.variants import (
    ablation_commands,
    ablation_tag,
    evaluate_runs,
    run_logged,
    runs_table,
)
from rtaw_marl.training.zoo import recipe
from rtaw_marl.utils.atomic import atomic_write

ROOT = Path(__file__).resolve().parents[2]
RUNS = ROOT / "runs" / "ablation"


def train(args: argparse.Namespace, seed: int) -> Path:
    """Train one ablated run (after its first stage); returns its best checkpoint."""
    run_dir = RUNS / f"{args.name}_{ablation_tag(args.overrides, args.first)}_s{seed}"
    cmds = ablation_commands(
        args.name, args.overrides, seed, run_dir, args.first, args.first_frames
    )
    for cmd in cmds:
        out = Path(next(c for c in cmd if c.startswith("output_dir=")).split("=", 1)[1])
        shutil.rmtree(out, ignore_errors=True)
        run_logged(cmd, out.with_suffix(".log"))
    return run_dir / "checkpoints" / "best.pt"


def describe(args: argparse.Namespace) -> str:
    first = f"first {args.first_frames} frames with {' '.join(args.first)}; " if args.first else ""
    return first + (" ".join(args.overrides) or "then the entry's own settings")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("name", help="a zoo entry with a seed_spread.py reference")
    parser.add_argument("overrides", nargs="*", help="rtaw-train overrides, e.g. model.x=y")
    parser.add_argument("--first", nargs="+", default=[], help="overrides of a first stage")
    parser.add_argument("--first-frames", type=int, default=0, help="PPO frames of it")
    parser.add_argument("--train-seeds", type=int, nargs="+", default=[0, 1])
    parser.add_argument("--jobs", type=int, default=1, help="training runs at once")
    args = parser.parse_args()
    recipe(args.name)
    if not args.overrides and not args.first:
        parser.error("give overrides, a --first stage, or both")
    reference = ROOT / "benchmarks" / "data" / f"seed_spread_{args.name}.json"
    if not reference.is_file():
        parser.error(
            f"{reference} is missing: run benchmarks/scripts/seed_spread.py {args.name} first"
        )
    stored = json.loads(reference.read_text())
    with ThreadPoolExecutor(max_workers=args.jobs) as pool:
        paths = list(pool.map(lambda k: train(args, k), args.train_seeds))
    tag = ablation_tag(args.overrides, args.first)
    labelled = {f"ablated seed {k}": p for k, p in zip(args.train_seeds, paths, strict=True)}
    ablated = evaluate_runs(args.name, labelled, stored["seeds"], RUNS / f"eval_{tag}", args.jobs)
    ttd = {**stored["ttd"], **{k: v for k, v in ablated.items() if k in labelled}}
    print(runs_table(ttd))
    runs = np.mean([v for k, v in ttd.items() if k.startswith("seed")], axis=0)
    ablated_runs = np.mean([v for k, v in ttd.items() if k.startswith("ablated")], axis=0)
    print(
        f"\nMean of {len(labelled)} ablated runs ({describe(args)}) vs mean of the reference "
        f"runs, paired over {len(stored['seeds'])} evaluation seeds: "
        f"{vs(runs, ablated_runs)} (positive: ablation better)"
    )
    out = ROOT / "benchmarks" / "data" / f"ablation_{args.name}_{tag}.json"
    payload = {"seeds": stored["seeds"], "run": describe(args), "ttd": ttd}
    atomic_write(out, lambda fh: fh.write(json.dumps(payload).encode()))
    return 0


if __name__ == "__main__":
    sys.exit(main())
