"""Does fine-tuning with collision-aware execution pay? A*-trained RTAW+ continued with SIPP.

Usage::

    python experiments/sipp_finetune.py --jobs 2            # train, then evaluate
    python experiments/sipp_finetune.py --eval-only         # evaluate the runs there

For each layout A-E, continues the best checkpoint of the shipped 10-robot RTAW+ run
(``runs/pretrained/<p>_astar_m10_plus``, trained with A*: train it first with
``train_pretrained.py``) with SIPP execution on the navigation table's setting (10 robots,
50 designated tasks, no completion noise) for ``--frames`` more PPO frames
(``resume_new_scenario=true``), selected on seeds 1000-1009, into
``runs/sipp_finetune/<p>``. Then evaluates each best checkpoint on the table's SIPP and
CBS rows (seeds 0-19) and pairs it per seed with the stored navigation table
(``docs/data/navigators.json``: the A*-trained RTAW+ and the rules). Prints one markdown
row per layout and navigator plus pooled lines; per-seed TTDs go to
``docs/data/sipp_finetune.json``.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

from paper_tables import vs

from rtaw_marl.evaluation import evaluate
from rtaw_marl.models.checkpoint import load_checkpoint
from rtaw_marl.policies.network import load_policy
from rtaw_marl.sim.builder import SimSpec
from rtaw_marl.utils.atomic import atomic_write

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "docs" / "data"
RUNS = ROOT / "runs" / "sipp_finetune"
SEEDS = list(range(20))
LAYOUTS = "ABCDE"
NAVIGATORS = ("sipp", "cbs")
#: The navigation table's setting (experiments/paper_tables.py ``navigators``).
ENV = {"num_robots": 10, "num_tasks": 50, "queue_len": 10, "noise_mean": 0.0, "noise_var": 0.0}


def command(layout: str, frames: int) -> list[str]:
    """The rtaw-train command continuing layout ``layout``'s A*-trained RTAW+ with SIPP."""
    base = ROOT / "runs" / "pretrained" / f"{layout}_astar_m10_plus" / "checkpoints" / "best.pt"
    start = int(load_checkpoint(base)["frames"])
    exe = str(Path(sys.executable).with_name("rtaw-train"))
    return [
        exe, f"layout={layout}", "navigator=sipp",
        *(f"env.{k}={v}" for k, v in ENV.items()), "model=rtaw_plus", "algo=ppo",
        f"frames={start + frames}", "eval.every_frames=20480",
        "eval.seeds=[1000,1001,1002,1003,1004,1005,1006,1007,1008,1009]", "seed=0",
        f"resume={base}", "resume_new_scenario=true", f"output_dir={RUNS / layout}",
        "progress=false",
    ]  # fmt: skip


def train(layout: str, frames: int) -> str:
    """Run :func:`command` for ``layout`` (its log in ``runs/sipp_finetune/<p>.log``)."""
    RUNS.mkdir(parents=True, exist_ok=True)
    with (RUNS / f"{layout}.log").open("w") as log:
        subprocess.run(command(layout, frames), check=True, cwd=ROOT, stdout=log,
                       stderr=subprocess.STDOUT)  # fmt: skip
    best = load_checkpoint(RUNS / layout / "checkpoints" / "best.pt")
    return f"{layout}: best selection TTD {best['eval']['ttd']:.1f} at {best['frames']} frames"


def report() -> None:
    """Evaluate every fine-tuned policy on the SIPP and CBS rows; print and store."""
    table = json.loads((DATA / "navigators.json").read_text())
    if table["seeds"] != SEEDS:
        raise SystemExit("error: navigators.json holds other seeds; regenerate that table")
    print("| setting | fine-tuned vs A*-trained RTAW+ | vs MPDM | vs RBTS | vs lookahead |")
    print("|---|---|---|---|---|")
    out: dict[str, list[float]] = {}
    pooled: dict[str, dict[str, list[float]]] = {}
    for nav in NAVIGATORS:
        for p in LAYOUTS:
            layout = {"name": "preset", "preset": p, "width": 60, "height": 60}
            sim = SimSpec.of({**ENV}, layout, nav, "designated").build()
            policy = load_policy(RUNS / p / "checkpoints" / "best.pt", name="tuned")
            ttd = evaluate(sim, {"tuned": policy}, SEEDS)["tuned"]["ttd"]
            row = table["rows"][f"{p}, {nav}"]
            out[f"{p}, {nav}"] = ttd
            acc = pooled.setdefault(nav, {})
            for label in ("RTAW+", "MPDM", "RBTS", "lookahead"):
                acc.setdefault(label, []).extend(row[label])
            acc.setdefault("tuned", []).extend(ttd)
            cells = " | ".join(vs(row[b], ttd) for b in ("RTAW+", "MPDM", "RBTS", "lookahead"))
            print(f"| {p}, {nav} | {cells} |", flush=True)
    for nav, acc in pooled.items():
        cells = "; ".join(f"vs {b} {vs(acc[b], acc['tuned'])}"
                          for b in ("RTAW+", "MPDM", "RBTS", "lookahead"))  # fmt: skip
        print(f"- {nav}, pooled over A-E: fine-tuned {cells} (n={len(acc['tuned'])})")
    text = json.dumps({"seeds": SEEDS, "rows": out}, indent=1) + "\n"
    atomic_write(DATA / "sipp_finetune.json", lambda fh: fh.write(text.encode()))


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
    report()
    return 0


if __name__ == "__main__":
    sys.exit(main())
