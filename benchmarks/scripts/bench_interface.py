"""Benchmark the policy interface end to end, against another commit, in one run.

Measures, at ``M`` robots on layout C (A*, 500-task episodes):

* ``README loop``: the README's loop, the shipped RTAW+ acting with ``policy.act(obs)``
  on ``warehouse_v1`` observations (``agent_iter`` / ``last`` / ``step``) -- decisions/s;
* ``act_sim``: the same policy on the bare simulator (``run_episode``), the evaluation
  path -- decisions/s;
* ``AEC + observe_all``: ``observe_all()`` of every robot's view per step (what the
  TorchRL wrapper route reads) -- steps/s (needs the same API in both trees).

Each figure runs in a fresh process per tree, alternating the trees ``--repeats`` times,
and the medians and the ratio (this tree / the other) are printed. The other tree is a
``git worktree`` of ``--against`` (default ``b136941``, before issue 22's redesign).

Usage::

    .venv/bin/python -m benchmarks.scripts.bench_interface --repeats 3
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

#: One measurement in a fresh process: prints {"figure": value}.
PROBE = r"""
import json, sys, time
import numpy as np
import torch
from rtaw_marl import warehouse_v1
from rtaw_marl.evaluation import run_episode
from rtaw_marl.policies.network import load_policy as _load
from rtaw_marl.policies.pretrained.registry import pretrained_path
torch.set_num_threads(1)
m, figure = int(sys.argv[1]), sys.argv[2]
policy = _load(pretrained_path("C_astar_m100_long_plus"))
kwargs = dict(num_robots=m, num_tasks=500, layout={"name": "preset", "preset": "C"},
              navigator="astar")
env = warehouse_v1.env(**kwargs)
if figure == "act_sim":
    sim = env.unwrapped.sim
    run_episode(sim, policy, 1)  # warm-up
    t = time.perf_counter(); run_episode(sim, policy, 0); dt = time.perf_counter() - t
    print(json.dumps({figure: 500 / dt})); sys.exit()
env.reset(seed=1)
steps, start = 0, None
for agent in env.agent_iter():
    obs, reward, terminated, truncated, info = env.last()
    if start is None:
        start = time.perf_counter()
    if figure == "observe_all":
        env.unwrapped._views.observe_all()
        action = None if terminated or truncated else int(np.flatnonzero(obs["action_mask"])[0])
    else:
        action = None if terminated or truncated else policy.act(obs)
    env.step(action)
    steps += action is not None
print(json.dumps({figure: steps / (time.perf_counter() - start)}))
"""


def _measure(tree: Path, m: int, figure: str) -> float | None:
    env = {**os.environ, "PYTHONPATH": str(tree)}
    proc = subprocess.run(
        [sys.executable, "-c", PROBE, str(m), figure],
        env=env,
        cwd=tree,
        capture_output=True,
        text=True,
    )
    if proc.returncode != 0:
        return None
    return float(json.loads(proc.stdout.strip().splitlines()[-1])[figure])


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--against", default="b136941", help="the other commit")
    parser.add_argument("--robots", type=int, nargs="+", default=[10, 100])
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        other = Path(tmp) / "other"
        subprocess.run(["git", "-C", str(ROOT), "worktree", "add", "-q", "--detach", str(other),
                        args.against], check=True)  # fmt: skip
        try:
            rows = _table(other, args)
        finally:
            subprocess.run(["git", "-C", str(ROOT), "worktree", "remove", "--force", str(other)])
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores; "
          f"medians of {args.repeats} fresh processes per tree, alternated")  # fmt: skip
    print(f"| figure | M | this tree | {args.against} | ratio |\n|---|---|---|---|---|")
    print("\n".join(rows))
    return 0


def _table(other: Path, args: argparse.Namespace) -> list[str]:
    rows = []
    for figure, label in (("readme", "README loop, dec/s"), ("act_sim", "act_sim, dec/s"),
                          ("observe_all", "AEC + observe_all, steps/s")):  # fmt: skip
        for m in args.robots:
            ours, theirs = [], []
            for _ in range(args.repeats):
                ours.append(_measure(ROOT, m, figure))
                theirs.append(_measure(other, m, figure))
            a = statistics.median(v for v in ours if v is not None) if any(ours) else None
            ok = [v for v in theirs if v is not None]
            b = statistics.median(ok) if ok else None
            ratio = f"{a / b:.2f}" if a and b else "-"
            cell = lambda v: "-" if v is None else f"{v:,.0f}"  # noqa: E731
            rows.append(f"| {label} | {m} | {cell(a)} | {cell(b)} | {ratio} |")
            print(rows[-1], file=sys.stderr, flush=True)
    return rows


if __name__ == "__main__":
    sys.exit(main())
