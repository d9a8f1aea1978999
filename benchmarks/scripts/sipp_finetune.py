"""Does fine-tuning with collision-aware execution pay? A*-trained RTAW+ continued with SIPP.

Usage::

    python -m benchmarks.scripts.sipp_finetune --jobs 2            # train, then evaluate
    python -m benchmarks.scripts.sipp_finetune --eval-only         # evaluate the runs there

For each layout A-E, continues the best checkpoint of the zoo's 10-robot RTAW+ run
(``runs/pretrained/<p>_astar_m10_plus``, trained with A*: ``rtaw-zoo <p>_astar_m10_plus``
first) with SIPP execution on the navigation table's setting (10 robots, 50 designated
tasks, no completion noise) for ``--frames`` more PPO frames
(:func:`benchmarks.variants.sipp_finetune_command`), selected on seeds
1000-1009, into ``runs/sipp_finetune/<p>``. Then evaluates each best checkpoint on the
``navigators`` study's SIPP and CBS rows (seeds 0-19) and pairs it per seed with the
stored table (``benchmarks/data/navigators.json``: the A*-trained RTAW+ and the rules). Prints
one markdown row per layout and navigator plus pooled lines; per-seed TTDs go to
``benchmarks/data/sipp_finetune.json``.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

from benchmarks.studies import STUDIES
from benchmarks.study import (
    Study,
    StudyResult,
    checkpoint,
    load_result,
    run_study,
)
from benchmarks.tables import vs
from benchmarks.variants import run_logged, sipp_finetune_command
from rtaw_marl.evaluation.report import markdown_table
from rtaw_marl.models.checkpoint import load_checkpoint
from rtaw_marl.training.zoo import RUNS as ZOO_RUNS
from rtaw_marl.utils.atomic import atomic_write

ROOT = Path(__file__).resolve().parents[2]
DATA = ROOT / "benchmarks" / "data"
RUNS = ROOT / "runs" / "sipp_finetune"
SEEDS = list(range(20))
LAYOUTS = "ABCDE"
NAVIGATORS = ("sipp", "cbs")
BASELINES = ("RTAW+", "MPDM", "RBTS", "lookahead")


def train(layout: str, frames: int) -> str:
    """Fine-tune ``layout``'s RTAW+ (its log in ``runs/sipp_finetune/<p>.log``)."""
    base = ROOT / ZOO_RUNS / f"{layout}_astar_m10_plus" / "checkpoints" / "best.pt"
    start = int(load_checkpoint(base)["frames"])
    cmd = sipp_finetune_command(layout, frames, RUNS / layout, start, ROOT / ZOO_RUNS)
    run_logged(cmd, RUNS / f"{layout}.log")
    ckpt = load_checkpoint(best(layout))
    return f"{layout}: best selection TTD {ckpt['eval']['ttd']:.1f} at {ckpt['frames']} frames"


def best(layout: str) -> Path:
    """The fine-tuned run's best checkpoint of preset ``layout``."""
    return RUNS / layout / "checkpoints" / "best.pt"


def evaluate_tuned() -> StudyResult:
    """The fine-tuned policies on the navigators study's SIPP and CBS cells."""
    cells = [
        dataclasses.replace(c, policies={"tuned": checkpoint(best(c.key.split(", ")[0]))})
        for c in STUDIES["navigators"].cells(SEEDS)
        if c.key.split(", ")[1] in NAVIGATORS
    ]
    study = Study(name="sipp_finetune", description="", cells=lambda _: cells,
                  render=lambda r, _: "", page=None, store=False)  # fmt: skip
    return run_study(study, SEEDS, RUNS / "eval")


def report(result: StudyResult) -> str:
    """Rows per layout and navigator against the stored table, then pooled lines."""
    table = load_result(DATA / "navigators.json")
    if table is None or table.seeds != SEEDS:
        raise SystemExit("error: navigators.json is missing or holds other seeds")
    rows = {k: {**table.ttd[k], **v} for k, v in result.ttd.items()}
    head = ["setting", "fine-tuned vs A*-trained RTAW+", *(f"vs {b}" for b in BASELINES[1:])]
    body = [[k, *(vs(t[b], t["tuned"]) for b in BASELINES)] for k, t in rows.items()]
    lines = []
    for nav in NAVIGATORS:
        # Pooled as one paired sample: every layout's seeds together.
        mine = [t for k, t in rows.items() if k.endswith(f", {nav}")]
        acc = {label: [x for t in mine for x in t[label]] for label in (*BASELINES, "tuned")}
        cells = "; ".join(f"vs {b} {vs(acc[b], acc['tuned'])}" for b in BASELINES)
        lines.append(f"- {nav}, pooled over A-E: fine-tuned {cells} (n={len(acc['tuned'])})")
    return markdown_table(head, body) + "\n\n" + "\n".join(lines)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=81_920, help="PPO frames with SIPP")
    parser.add_argument("--jobs", type=int, default=1, help="training runs at once")
    parser.add_argument("--eval-only", action="store_true", help="evaluate the existing runs")
    args = parser.parse_args()
    if not args.eval_only:
        with ThreadPoolExecutor(max_workers=args.jobs) as pool:
            for line in pool.map(lambda p: train(p, args.frames), LAYOUTS):
                print(line, flush=True)
    result = evaluate_tuned()
    print(report(result))
    rows = {key: ttd["tuned"] for key, ttd in result.ttd.items()}
    text = json.dumps({"seeds": SEEDS, "rows": rows}, indent=1) + "\n"
    atomic_write(DATA / "sipp_finetune.json", lambda fh: fh.write(text.encode()))
    return 0


if __name__ == "__main__":
    sys.exit(main())
