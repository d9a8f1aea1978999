"""Benchmark of the training stack: end-to-end PPO throughput, collection alone, policy
latency, time to beat MPDM.

The end-to-end table runs ``train()`` as ``rtaw-train`` does (the default ``algo=ppo``;
N = 10, A*, the default 60x60 warehouse, designated tasks) for M = 10, 100 and 1000
robots with 1 and 2 collector workers, and reports frames per second over the whole run
(start-up, evaluation and checkpoints included) and in steady state (the iterations
only), with the seconds per 8192-frame batch spent collecting, computing advantages
(GAE), updating, syncing weights and evaluating + checkpointing.

Usage::

    python -m benchmarks.scripts.bench_train              # everything (about 10 minutes)
    python -m benchmarks.scripts.bench_train --e2e-only   # the end-to-end table only
    python -m benchmarks.scripts.bench_train --e2e-only --model rtaw_plus  # RTAW+, M = 100, 1000
    python -m benchmarks.scripts.bench_train --train      # + wall time for rtaw-train to beat MPDM
    python -m benchmarks.scripts.bench_train --quick      # tiny sizes, a smoke run
    python -m benchmarks.scripts.bench_train --backend ray  # local vs Ray actors, end to end

``--backend ray`` runs only the end-to-end comparison: for M = 10 and 100, ``train()`` with
the local backend (1 and 2 worker processes) and with ``collector=ray`` (1 and 2 actors on
a local Ray cluster that each run starts, as ``rtaw-train collector=ray`` does), in one
run, medians of ``--repeats`` runs; the learner's seconds per batch (GAE + update) bound
the speed-up more collectors can give (docs/cluster.md).

Prints markdown tables; ``--output PATH`` also writes them to a file. Medians of
``--repeats`` measurements taken in one run.
"""

from __future__ import annotations

import argparse
import platform
import statistics
import sys
import tempfile
import time
from functools import partial
from pathlib import Path

import numpy as np
import torch
from torchrl.collectors import Collector, MultiSyncCollector

from rtaw_marl.config import compose, to_typed
from rtaw_marl.envs.torchrl import BatchedWarehouseEnv
from rtaw_marl.models.actor_critic import make_actor
from rtaw_marl.models.checkpoint import build_networks
from rtaw_marl.models.config import RTAWConfig
from rtaw_marl.sim.builder import SimSpec

MAPS = Path(__file__).resolve().parents[3] / "shared" / "maps"


def _layout() -> dict:
    usc = MAPS / "rtaw" / "usc_64.cfg"
    if usc.is_file():
        return {"name": "file", "path": str(usc)}
    return {"name": "open", "width": 64, "height": 64}


def _make_env(m: int, envs: int, seed: int, layout: dict) -> BatchedWarehouseEnv:
    return BatchedWarehouseEnv(
        SimSpec.of(
            {"num_robots": m, "num_tasks": 500, "queue_len": 10}, layout, "astar", "designated"
        ),
        num_envs=envs,
        seed=seed,
    )


def bench_collection(
    m: int, workers: int, envs: int, batch: int, batches: int, repeats: int
) -> list[float]:
    """Collected frames per second (policy sampling included), one value per repeat."""
    layout = _layout()
    actor = make_actor(build_networks(RTAWConfig())[0])
    rates = []
    for rep in range(repeats):
        kwargs = {
            "frames_per_batch": batch,
            "total_frames": batch * (batches + 1),
            "auto_register_policy_transforms": False,
        }
        fns = [partial(_make_env, m, envs, 100 * rep + w, layout) for w in range(workers)]
        if workers == 1:
            collector = Collector(fns[0], actor, **kwargs)
        else:
            collector = MultiSyncCollector(fns, actor, **kwargs)
        it = iter(collector)
        next(it)  # warm-up: process start, JIT load, first distance fields
        start = time.perf_counter()
        frames = sum(next(it).numel() for _ in range(batches))
        rates.append(frames / (time.perf_counter() - start))
        collector.shutdown()
    return rates


@torch.no_grad()
def bench_latency(m: int, n: int, calls: int) -> float:
    """Median seconds of one policy forward (batch of one decision)."""
    net = build_networks(RTAWConfig())[0].eval()
    robots, tasks = torch.rand(1, m, 3), torch.rand(1, n, 6)
    agent, mask = torch.rand(1, 3), torch.ones(1, n, dtype=torch.bool)
    for _ in range(20):
        net(robots, tasks, agent, mask)
    times = []
    for _ in range(calls):
        start = time.perf_counter()
        net(robots, tasks, agent, mask)
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def bench_time_to_beat_mpdm(frames: int, every: int, algo: str) -> tuple[list[dict], float]:
    """Train on the default scenario; evaluation history and MPDM's TTD."""
    from rtaw_marl.training.ppo import train

    overrides = [
        f"frames={frames}",
        f"selection.every_frames={every}",
        f"algo={algo}",
        "progress=false",
    ]
    cfg = to_typed(compose("train", overrides))
    with tempfile.TemporaryDirectory() as tmp:
        result = train(cfg, tmp)
    return result.history, result.mpdm_ttd


PHASES = ("collect", "gae", "update", "sync", "eval_checkpoint")


#: ``--model rtaw_plus``: RTAW+ as the generalist trains (a fixed-size fleet summary for
#: its critic, so no ``[M, 3]`` input; two learner threads).
RTAW_PLUS = ("model=rtaw_plus", "model.fleet_summary=true", "torch_threads=2")


def bench_end_to_end(
    m: int, workers: int, frames: int, quick: bool, backend: str = "local", model: str = "rtaw"
) -> dict[str, float]:
    """One ``train()`` run; frames/s overall and in steady state, seconds per batch by phase."""
    from rtaw_marl.training.ppo import train

    overrides = [f"sim.num_robots={m}", f"collector.workers={workers}", f"frames={frames}",
                 f"selection.every_frames={frames // 2}", "progress=false",
                 f"collector.backend={backend}"]  # fmt: skip
    if model == "rtaw_plus":
        overrides += RTAW_PLUS
    if quick:
        overrides += ["algo.frames_per_batch=1024", "algo.minibatch_size=256"]
    cfg = to_typed(compose("train", overrides))
    with tempfile.TemporaryDirectory() as tmp:
        start = time.perf_counter()
        result = train(cfg, tmp)
        wall = time.perf_counter() - start
    batches = result.frames / cfg.algo.frames_per_batch
    steady = sum(result.timings.values())
    out = {"overall": result.frames / wall, "steady": result.frames / steady, "wall": wall}
    out.update({p: result.timings.get(f"time/{p}_s", 0.0) / batches for p in PHASES})
    return out


def end_to_end_table(quick: bool, model: str = "rtaw") -> list[str]:
    lines = [
        "| M | workers | frames | frames/s overall | frames/s steady | s per batch: collect "
        "/ GAE / update / sync / eval+ckpt | target |",
        "|---:|---:|---:|---:|---:|---|---|",
    ]
    targets = {10: ">= 10,000", 100: ">= 6,000", 1000: ">= 1,500"}
    sizes = [(10, 1, 8192)] if quick else [
        (10, 1, 163840), (10, 2, 163840), (100, 1, 81920), (100, 2, 81920),
        (1000, 1, 16384),
    ]  # fmt: skip
    if model == "rtaw_plus":  # issue 24's targets
        targets = {10: "", 100: ">= 10,000", 1000: ">= 3,000"}
        sizes = [(10, 1, 8192)] if quick else [
            (100, 1, 81920), (100, 2, 81920), (1000, 1, 49152), (1000, 2, 49152),
        ]  # fmt: skip
    for m, workers, frames in sizes:
        r = bench_end_to_end(m, workers, frames, quick, model=model)
        phases = " / ".join(f"{r[p]:.2f}" for p in PHASES)
        lines.append(
            f"| {m} | {workers} | {frames:,} | {r['overall']:,.0f} | {r['steady']:,.0f} | "
            f"{phases} | {targets[m]} |"
        )
        print(lines[-1], flush=True)
    return lines


def backend_table(quick: bool, repeats: int) -> list[str]:
    """Local worker processes against Ray actors, end to end; medians of ``repeats``."""
    lines = [
        "| M | backend | collectors | frames | frames/s overall | frames/s steady | s per "
        "batch: collect / GAE / update / sync / eval+ckpt | runs |",
        "|---:|---|---:|---:|---:|---:|---|---:|",
    ]
    sizes = [(10, 8192)] if quick else [(10, 81920), (100, 40960)]
    for m, frames in sizes:
        for backend in ("local", "ray"):
            for workers in (1, 2):
                runs = [
                    bench_end_to_end(m, workers, frames, quick, backend) for _ in range(repeats)
                ]
                r = {k: statistics.median(run[k] for run in runs) for k in runs[0]}
                phases = " / ".join(f"{r[p]:.2f}" for p in PHASES)
                lines.append(
                    f"| {m} | {backend} | {workers} | {frames:,} | {r['overall']:,.0f} | "
                    f"{r['steady']:,.0f} | {phases} | {len(runs)} |"
                )
                print(lines[-1], flush=True)
    return lines


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--quick", action="store_true", help="tiny sizes (smoke run)")
    parser.add_argument("--train", action="store_true", help="also time training to beat MPDM")
    parser.add_argument("--train-frames", type=int, default=204800)
    parser.add_argument("--algo", default="ppo_fast", help="algo config for --train")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--e2e-only", action="store_true", help="only the end-to-end table")
    parser.add_argument(
        "--backend", choices=("local", "ray"), default="local",
        help="ray: only the end-to-end table of local workers vs Ray actors",
    )  # fmt: skip
    parser.add_argument("--output", type=Path, default=None)
    parser.add_argument(
        "--model", choices=("rtaw", "rtaw_plus"), default="rtaw",
        help="the end-to-end table's network (rtaw_plus: as the generalist trains)",
    )  # fmt: skip
    args = parser.parse_args()
    torch.set_num_threads(1)
    lines = [
        f"machine: {platform.platform()}, {torch.get_num_threads()} torch thread, "
        f"python {platform.python_version()}, torch {torch.__version__}",
        "",
    ]
    if args.backend == "ray":
        lines += backend_table(args.quick, 1 if args.quick else args.repeats)
        print("\n".join(lines))
        if args.output:
            args.output.write_text("\n".join(lines) + "\n")
        return 0
    lines += end_to_end_table(args.quick, args.model)
    if args.e2e_only:
        print("\n".join(lines))
        if args.output:
            args.output.write_text("\n".join(lines) + "\n")
        return 0
    lines += [
        "",
        "| M | workers | envs/worker | frames/s (median) | spread | target |",
        "|---:|---:|---:|---:|---|---|",
    ]
    sizes = [10] if args.quick else [10, 100, 1000]
    repeats = 1 if args.quick else args.repeats
    for m in sizes:
        for workers in (1, 2):
            envs = 64 if m <= 100 else 32
            batch, batches = (256, 1) if args.quick else (4096 if m <= 100 else 2048, 4)
            if args.quick:
                envs = 16
            rates = bench_collection(m, workers, envs, batch, batches, repeats)
            target = ">= 20,000" if m == 100 else ""
            lines.append(
                f"| {m} | {workers} | {envs} | {statistics.median(rates):,.0f} | "
                f"{min(rates):,.0f}-{max(rates):,.0f} | {target} |"
            )
            print(lines[-1], flush=True)
    lines += ["", "| M | N | forward latency (ms, median) |", "|---:|---:|---:|"]
    calls = 50 if args.quick else 500
    grid = (
        [(10, 10), (1000, 10)]
        if args.quick
        else [(10, 10), (100, 10), (1000, 10), (10000, 10), (100, 2), (100, 50), (100, 100)]
    )
    lat = {}
    for m, n in grid:
        lat[(m, n)] = bench_latency(m, n, calls)
        lines.append(f"| {m} | {n} | {1e3 * lat[(m, n)]:.3f} |")
        print(lines[-1], flush=True)
    ms = [m for m, n in grid if n == 10]
    if len(ms) > 2:
        slope, intercept = np.polyfit(ms, [lat[(m, 10)] * 1e3 for m in ms], 1)
        lines.append(
            f"\nlinear fit over M (N=10): {intercept:.3f} ms + {slope * 1e3:.3f} ms per 1000 robots"
        )
    if args.train:
        history, mpdm = bench_time_to_beat_mpdm(args.train_frames, 10240, args.algo)
        lines += [
            "",
            f"algo={args.algo}; MPDM TTD on the evaluation seeds: {mpdm:.1f}",
            "",
            "| frames | wall s | RTAW TTD | vs MPDM |",
            "|---:|---:|---:|---:|",
        ]
        for row in history:
            lines.append(
                f"| {row['frames']} | {row['wall_s']:.0f} | {row['ttd']:.1f} | "
                f"{row['improvement_pct']:+.1f}% |"
            )
        first = next((r for r in history if r["ttd"] < mpdm), None)
        lines.append(
            f"\nfirst evaluation below MPDM: {first['wall_s']:.0f} s ({first['frames']} frames)"
            if first
            else "\nnever below MPDM in this run"
        )
    text = "\n".join(lines)
    print(text)
    if args.output:
        args.output.write_text(text + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
