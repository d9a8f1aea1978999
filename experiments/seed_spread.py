"""The spread between training runs: one registry entry trained with several seeds.

Usage::

    python experiments/seed_spread.py C_astar_m10_plus --train-seeds 1 2 --jobs 2
    python experiments/seed_spread.py C_astar_m10_plus --train-seeds 1 2 --eval-only
    # A Table II row: the 100-robot base with each seed, then its 500-robot curriculum.
    python experiments/seed_spread.py open300_direct_m100_random_plus --train-seeds 1 2
    python experiments/seed_spread.py open300_direct_m500_random_plus --train-seeds 1 2

Trains the entry's exact ``rtaw-train`` command with ``seed=K`` for each extra training
seed (into ``runs/seeds/<name>_s<K>``; seed 0 is the shipped policy), then evaluates every
run's best checkpoint beside MPDM, RBTS and lookahead on the evaluation seeds 0..N-1 of
the entry's own scenario, and prints each run's paired difference against each rule.
Per-seed TTDs go to ``docs/data/seed_spread_<name>.json``.

A curriculum entry (Table II's 500-robot RTAW+, the registry's ``CURRICULUM``) with seed K
continues its base trained with the same seed K (``runs/seeds/<base>_s<K>``, so run the
base first), so each seed is a whole pipeline. It is evaluated on the Table II rows of its
grid (5,000 tasks; ``--robots``, default 500 and 1000), paired with the rules and the
shipped policy (seed 0) stored in ``docs/data/table2.json`` on the same seeds.
"""

from __future__ import annotations

import argparse
import json
import shutil
import subprocess
import sys
from concurrent.futures import ProcessPoolExecutor, ThreadPoolExecutor
from functools import partial
from pathlib import Path

import paper_tables as pt
import torch

from rtaw_marl.config import compose, to_typed
from rtaw_marl.evaluation import evaluate
from rtaw_marl.evaluation.stats import paired_difference
from rtaw_marl.models.checkpoint import load_checkpoint
from rtaw_marl.policies import make_baseline
from rtaw_marl.policies.network import load_policy
from rtaw_marl.policies.pretrained.registry import (
    CURRICULUM,
    PRETRAINED,
    curriculum_overrides,
    pretrained_path,
    train_command,
)
from rtaw_marl.sim.builder import SimSpec
from rtaw_marl.utils.atomic import atomic_write

ROOT = Path(__file__).resolve().parents[1]
SEEDS_DIR = ROOT / "runs" / "seeds"
RULES = ("mpdm", "rbts", "lookahead")
#: docs/data/table2.json's labels of the rules and of the shipped RTAW+.
TABLE2_LABELS = {"mpdm": "MPDM", "rbts": "RBTS", "lookahead": "lookahead", "seed 0": "RTAW+"}


def seed_command(name: str, seed: int, run_dir: Path) -> list[str]:
    """The command training ``name`` with ``seed`` into ``run_dir``: the registry's with
    ``seed=K``; a curriculum entry continues its base's best checkpoint of the same seed."""
    if name not in CURRICULUM:
        return [*train_command(name, run_dir), f"seed={seed}"]
    base = SEEDS_DIR / f"{CURRICULUM[name][0]}_s{seed}" / "checkpoints" / "best.pt"
    if not base.is_file():
        raise SystemExit(
            f"error: {base} is missing; train the base first: python "
            f"experiments/seed_spread.py {CURRICULUM[name][0]} --train-seeds {seed}"
        )
    frames = int(load_checkpoint(base)["frames"])
    exe = train_command(name, run_dir)[0]
    overrides = curriculum_overrides(name, str(base), frames)
    return [exe, *overrides, f"output_dir={run_dir}", "progress=false", f"seed={seed}"]


def train_seed(name: str, seed: int) -> Path:
    """Train ``name`` with ``seed``; returns the best checkpoint."""
    run_dir = SEEDS_DIR / f"{name}_s{seed}"
    shutil.rmtree(run_dir, ignore_errors=True)
    cmd = seed_command(name, seed, run_dir)
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


def table2_rows(name: str, robots: list[int], seeds: list[int]) -> list[dict]:
    """The Table II jobs whose RTAW+ is curriculum entry ``name``, with their stored
    rules and shipped-policy TTDs (``"stored"``)."""
    saved = pt.load_saved("table2", seeds)
    if not saved:
        raise SystemExit("error: run python experiments/paper_tables.py table2 first")
    jobs = [
        job for job in pt.table2_jobs(seeds)
        if pt.scenario_of(job, "RTAW+") + "_plus" == name and job["env"]["num_robots"] in robots
    ]  # fmt: skip
    for job in jobs:
        row = saved[job["key"]]
        job["stored"] = {label: row[key] for label, key in TABLE2_LABELS.items()}
    return jobs


def evaluate_table2_row(job: dict, checkpoints: dict[int, Path]) -> dict[str, list[float]]:
    """The stored TTDs of ``job``'s row plus each extra training run's, on its seeds."""
    torch.set_num_threads(1)  # one decision at a time: more threads only contend
    sim = SimSpec.of(job["env"], job["layout"], job["navigator"], job["tasks"]).build()
    policies = {f"seed {k}": load_policy(path) for k, path in checkpoints.items()}
    res = evaluate(sim, policies, job["seeds"])
    return {**job["stored"], **{label: r["ttd"] for label, r in res.items()}}


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
    parser.add_argument(
        "--robots", type=int, nargs="+", default=[500, 1000],
        help="a curriculum entry's Table II rows: their robot counts",
    )  # fmt: skip
    args = parser.parse_args()
    if args.name not in PRETRAINED:
        parser.error(f"unknown entry {args.name!r}; valid: {', '.join(PRETRAINED)}")
    if args.eval_only:
        runs = {
            k: SEEDS_DIR / f"{args.name}_s{k}" / "checkpoints" / "best.pt" for k in args.train_seeds
        }
    else:
        with ThreadPoolExecutor(max_workers=args.jobs) as pool:
            paths = pool.map(lambda k: train_seed(args.name, k), args.train_seeds)
            runs = dict(zip(args.train_seeds, paths, strict=True))
    seeds = list(range(args.seeds))
    if args.name in CURRICULUM:
        jobs = table2_rows(args.name, args.robots, seeds)
        with ProcessPoolExecutor(max_workers=args.jobs) as pool:
            evaluated = pool.map(partial(evaluate_table2_row, checkpoints=runs), jobs)
            rows = dict(zip([job["key"] for job in jobs], evaluated, strict=True))
        payload = {"seeds": seeds, "rows": rows}
        text = "\n\n".join(f"Table II row `{key}`:\n\n{report(t)}" for key, t in rows.items())
    else:
        ttd = evaluate_runs(args.name, {0: pretrained_path(args.name), **runs}, seeds)
        payload, text = {"seeds": seeds, "ttd": ttd}, report(ttd)
    out = ROOT / "docs" / "data" / f"seed_spread_{args.name}.json"
    atomic_write(out, lambda fh: fh.write(json.dumps(payload).encode()))
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
