"""The spread between training runs: one zoo entry trained with several seeds.

Usage::

    python -m benchmarks.scripts.seed_spread C_astar_m10_plus --train-seeds 1 2 --jobs 2
    python -m benchmarks.scripts.seed_spread C_astar_m10_plus --train-seeds 1 2 --eval-only
    # A Table II row: the 100-robot base with each seed, then its 500-robot curriculum.
    python -m benchmarks.scripts.seed_spread open300_direct_m100_random_plus --train-seeds 1 2
    python -m benchmarks.scripts.seed_spread open300_direct_m500_random_plus --train-seeds 1 2

Trains the entry's recipe with ``seed=K`` for each extra training seed
(:func:`benchmarks.variants.seed_command`, into ``runs/seeds/<name>_s<K>``; seed
0 is the shipped policy), then evaluates every run's best checkpoint beside MPDM, RBTS
and lookahead on the evaluation seeds 0..N-1 of the entry's own scenario, and prints
each run's paired difference against each rule. Per-seed TTDs go to
``benchmarks/data/seed_spread_<name>.json``.

A curriculum entry (Table II's 500-robot RTAW+) with seed K continues its base trained
with the same seed K (``runs/seeds/<base>_s<K>``, so run the base first). It is
evaluated on the Table II rows of its grid (``--robots``, default 500 and 1000), paired
with the rules and the shipped policy (seed 0) stored in ``benchmarks/data/table2.json``
(``python -m benchmarks.run table2``) on the same seeds.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import shutil
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

from benchmarks.studies import STUDIES
from benchmarks.study import Study, checkpoint, load_result, run_study
from benchmarks.variants import evaluate_runs, run_logged, runs_table, seed_command
from rtaw_marl.policies.pretrained.registry import pretrained_path
from rtaw_marl.training.zoo import recipe
from rtaw_marl.utils.atomic import atomic_write

ROOT = Path(__file__).resolve().parents[2]
SEEDS_DIR = ROOT / "runs" / "seeds"
#: benchmarks/data/table2.json's labels of the rules and of the shipped RTAW+ -> this table's.
TABLE2_LABELS = {"MPDM": "mpdm", "RBTS": "rbts", "lookahead": "lookahead", "RTAW+": "seed 0"}


def train_seed(name: str, seed: int) -> Path:
    """Train ``name`` with ``seed``; returns its best checkpoint."""
    run_dir = SEEDS_DIR / f"{name}_s{seed}"
    shutil.rmtree(run_dir, ignore_errors=True)
    run_logged(seed_command(name, seed, run_dir, SEEDS_DIR), SEEDS_DIR / f"{name}_s{seed}.log")
    return run_dir / "checkpoints" / "best.pt"


def table2_rows(name: str, runs: dict[int, Path], robots: list[int], seeds: list[int]) -> dict:
    """Each Table II row whose RTAW+ is ``name``: its stored TTDs plus each run's."""
    stored = load_result(ROOT / "benchmarks" / "data" / "table2.json")
    if stored is None or stored.seeds != seeds:
        raise SystemExit("error: benchmarks/data/table2.json is missing or has other seeds")
    cells = [
        c for c in STUDIES["table2"].cells(seeds)
        if c.scenario.policies["RTAW+"] == name and c.scenario.sim["num_robots"] in robots
    ]  # fmt: skip
    policies = {f"seed {k}": checkpoint(path) for k, path in runs.items()}
    cells = [dataclasses.replace(c, policies=policies) for c in cells]
    study = Study(name=f"seed_spread_{name}", description="", cells=lambda _: cells,
                  render=lambda r, _: "", page=None, store=False)  # fmt: skip
    result = run_study(study, seeds, SEEDS_DIR / f"eval_{name}", workers=len(cells))
    return {
        c.key: {
            **{TABLE2_LABELS[k]: v for k, v in stored.ttd[c.key].items() if k in TABLE2_LABELS},
            **result.ttd[c.key],
        }
        for c in cells
    }


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("name", help="a zoo entry")
    parser.add_argument("--train-seeds", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--jobs", type=int, default=1, help="training runs at once")
    parser.add_argument("--seeds", type=int, default=20, help="evaluate on seeds 0..N-1")
    parser.add_argument("--eval-only", action="store_true", help="reuse trained runs")
    parser.add_argument(
        "--robots", type=int, nargs="+", default=[500, 1000],
        help="a curriculum entry's Table II rows: their robot counts",
    )  # fmt: skip
    args = parser.parse_args()
    entry = recipe(args.name)
    if args.eval_only:
        runs = {
            k: SEEDS_DIR / f"{args.name}_s{k}" / "checkpoints" / "best.pt" for k in args.train_seeds
        }
    else:
        with ThreadPoolExecutor(max_workers=args.jobs) as pool:
            paths = pool.map(lambda k: train_seed(args.name, k), args.train_seeds)
            runs = dict(zip(args.train_seeds, paths, strict=True))
    seeds = list(range(args.seeds))
    if entry.stage == "curriculum":
        rows = table2_rows(args.name, runs, args.robots, seeds)
        payload = {"seeds": seeds, "rows": rows}
        text = "\n\n".join(f"Table II row `{key}`:\n\n{runs_table(t)}" for key, t in rows.items())
    else:
        labelled = {f"seed {k}": path for k, path in runs.items()}
        output = SEEDS_DIR / f"eval_{args.name}"
        checkpoints = {"seed 0": pretrained_path(args.name), **labelled}
        ttd = evaluate_runs(args.name, checkpoints, seeds, output, args.jobs)
        payload, text = {"seeds": seeds, "ttd": ttd}, runs_table(ttd)
    out = ROOT / "benchmarks" / "data" / f"seed_spread_{args.name}.json"
    atomic_write(out, lambda fh: fh.write(json.dumps(payload).encode()))
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
