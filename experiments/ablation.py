"""Does a training aid pay? One registry entry retrained with extra overrides, several
training seeds, against the same entry's runs without them.

Usage::

    python experiments/seed_spread.py C_astar_m10_plus --train-seeds 1 2   # the reference
    python experiments/ablation.py C_astar_m10_plus model.critic_fleet=false --train-seeds 0 1
    # A curriculum: the first 204,800 PPO frames (and the warm start) with a queue of 5.
    python experiments/ablation.py C_astar_m10_plus --first env.queue_len=5 --first-frames 204800

Trains the entry's exact ``rtaw-train`` command plus the overrides with ``seed=K`` for
each training seed (into ``runs/ablation/<name>_<tag>_s<K>``). With ``--first``, a first
stage trains the entry's command plus those overrides for ``--first-frames`` PPO frames
(``<run>_first``), and the run continues it (``resume=<first>/checkpoints/last.pt
resume_new_scenario=true``) to the entry's own budget: a curriculum. Then it evaluates
each run's best
checkpoint on the evaluation seeds stored by ``seed_spread.py`` (its entry's own
scenario), and prints each run against the rules and, per evaluation seed, the mean of the
ablated runs against the mean of the reference runs (seed 0 is the shipped policy): a
paired difference over evaluation seeds, whose interval does not include the spread
between training runs, so read it beside the per-run lines. Per-seed TTDs go to
``docs/data/ablation_<name>_<tag>.json``.
"""

from __future__ import annotations

import argparse
import json
import re
import shutil
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
import seed_spread as ss

from rtaw_marl.evaluation.stats import paired_difference
from rtaw_marl.policies.pretrained.registry import PRETRAINED, train_command
from rtaw_marl.utils.atomic import atomic_write

ROOT = Path(__file__).resolve().parents[1]


def tag(overrides: list[str], first: list[str] | None = None) -> str:
    """A folder-safe name of the overrides: ``model.critic_fleet=false`` ->
    ``critic-fleet-false``; first-stage overrides get a ``first-`` prefix."""

    def name(o: str) -> str:
        return re.sub(r"[^A-Za-z0-9-]+", "-", o.rsplit(".", 1)[-1].replace("=", "-"))

    return "_".join([*(f"first-{name(o)}" for o in first or []), *map(name, overrides)])


def command(name: str, overrides: list[str], seed: int, run_dir: Path) -> list[str]:
    return [*train_command(name, run_dir), *overrides, f"seed={seed}"]


def run(cmd: list[str], log: Path) -> None:
    with log.open("w") as fh:
        subprocess.run(cmd, check=True, cwd=ROOT, stdout=fh, stderr=subprocess.STDOUT)


def train(name: str, overrides: list[str], seed: int, first: list[str], first_frames: int) -> Path:
    """Train one ablated run (after its first stage, with ``first``); returns its best
    checkpoint."""
    run_dir = ROOT / "runs" / "ablation" / f"{name}_{tag(overrides, first)}_s{seed}"
    shutil.rmtree(run_dir, ignore_errors=True)
    run_dir.parent.mkdir(parents=True, exist_ok=True)
    if first:
        first_dir = run_dir.with_name(run_dir.name + "_first")
        shutil.rmtree(first_dir, ignore_errors=True)
        stage = [*first, f"frames={first_frames}"]
        run(command(name, stage, seed, first_dir), first_dir.with_suffix(".log"))
        resume = [f"resume={first_dir}/checkpoints/last.pt", "resume_new_scenario=true"]
        overrides = [*overrides, *resume]
    run(command(name, overrides, seed, run_dir), run_dir.with_suffix(".log"))
    return run_dir / "checkpoints" / "best.pt"


def describe(args: argparse.Namespace) -> str:
    first = f"first {args.first_frames} frames with {' '.join(args.first)}; " if args.first else ""
    return first + (" ".join(args.overrides) or "then the entry's own settings")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("name", help="a registry entry with a seed_spread.py reference")
    parser.add_argument("overrides", nargs="*", help="rtaw-train overrides, e.g. model.x=y")
    parser.add_argument("--first", nargs="+", default=[], help="overrides of a first stage")
    parser.add_argument("--first-frames", type=int, default=0, help="PPO frames of it")
    parser.add_argument("--train-seeds", type=int, nargs="+", default=[0, 1])
    parser.add_argument("--jobs", type=int, default=1, help="training runs at once")
    args = parser.parse_args()
    if args.name not in PRETRAINED:
        parser.error(f"unknown entry {args.name!r}; valid: {', '.join(PRETRAINED)}")
    if not args.overrides and not args.first:
        parser.error("give overrides, a --first stage, or both")
    if bool(args.first) != (args.first_frames > 0):
        parser.error("--first and --first-frames > 0 go together")
    reference = ROOT / "docs" / "data" / f"seed_spread_{args.name}.json"
    if not reference.is_file():
        parser.error(f"{reference} is missing: run experiments/seed_spread.py {args.name} first")
    stored = json.loads(reference.read_text())
    with ThreadPoolExecutor(max_workers=args.jobs) as pool:
        paths = list(
            pool.map(
                lambda k: train(args.name, args.overrides, k, args.first, args.first_frames),
                args.train_seeds,
            )
        )
    ablated = ss.evaluate_runs(
        args.name, dict(zip(args.train_seeds, paths, strict=True)), stored["seeds"]
    )
    ttd = dict(stored["ttd"])
    ttd.update({f"ablated {label}": v for label, v in ablated.items() if label.startswith("seed")})
    print(ss.report(ttd))
    runs = [np.asarray(v) for k, v in ttd.items() if k.startswith("seed")]
    ablated_runs = [np.asarray(v) for k, v in ttd.items() if k.startswith("ablated")]
    d = paired_difference(np.mean(runs, axis=0), np.mean(ablated_runs, axis=0))
    mark = "*" if d.significant else ""
    print(
        f"\nMean of {len(ablated_runs)} ablated runs ({describe(args)}) vs mean of "
        f"{len(runs)} reference runs, paired over {len(stored['seeds'])} evaluation seeds: "
        f"{d.pct:+.1f}% [{d.pct_low:+.1f}, {d.pct_high:+.1f}]{mark} (positive: ablation better)"
    )
    out = ROOT / "docs" / "data" / f"ablation_{args.name}_{tag(args.overrides, args.first)}.json"
    payload = {"seeds": stored["seeds"], "run": describe(args), "ttd": ttd}
    atomic_write(out, lambda fh: fh.write(json.dumps(payload).encode()))
    return 0


if __name__ == "__main__":
    sys.exit(main())
