"""AEC env steps per second with the relational features, this tree against a baseline
revision, interleaved in one run.

Usage::

    python -m benchmarks.scripts.bench_aec                      # against 8d8e32f (before issue 24)
    python -m benchmarks.scripts.bench_aec --baseline HEAD~3 --repeats 5
    python -m benchmarks.scripts.bench_aec --quick              # M = 100 only, one repeat

Each measurement is a fresh interpreter importing ``rtaw_marl`` from one tree (the
baseline is checked out with ``git worktree`` into a temporary folder) that plays
``warehouse_v1.env(observation="full")`` (every key, the relational ones included) with
the first valid slot: one untimed warm-up stretch of 300 decisions, then steps per
second over the next ``--decisions`` (``env.last()`` + ``env.step()``, the order-enforcing
wrapper included). Settings: open 60x60 grid, ``direct``, random tasks at M = 100 and
1,000; open 300x300 at M = 10,000. The two trees alternate, ``--repeats`` times; the
table shows medians, the min-max spread, and the ratio of the medians.
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
#: The last commit before issue 24's changes to the features.
BASELINE = "8d8e32f"
SETTINGS = {100: 60, 1000: 60, 10_000: 300}

CHILD = """
import sys, time
from rtaw_marl import warehouse_v1
m, side, decisions = int(sys.argv[1]), int(sys.argv[2]), int(sys.argv[3])
env = warehouse_v1.env(num_robots=m, num_tasks=decisions + 400, navigator="direct",
                       tasks="random", layout={"name": "open", "width": side, "height": side})
env.reset(seed=2000)
done, start = 0, None
for agent in env.agent_iter():
    obs, _, term, trunc, _ = env.last()
    if term or trunc:
        break
    env.step(int(obs["action_mask"].argmax()))
    done += 1
    if done == 300:
        start = time.perf_counter()
    if done == 300 + decisions:
        break
print(decisions / (time.perf_counter() - start))
"""


def measure(tree: Path, m: int, decisions: int) -> float:
    """Steps per second of one fresh interpreter importing ``rtaw_marl`` from ``tree``."""
    out = subprocess.run(
        [sys.executable, "-c", CHILD, str(m), str(SETTINGS[m]), str(decisions)],
        capture_output=True, text=True, check=True, cwd=tree,
        env={"PYTHONPATH": str(tree), "PATH": "/usr/bin:/bin"},
    )  # fmt: skip
    return float(out.stdout.strip().splitlines()[-1])


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--baseline", default=BASELINE, help="git revision to compare with")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--decisions", type=int, default=3000)
    parser.add_argument("--quick", action="store_true", help="M = 100, one repeat")
    args = parser.parse_args()
    robots = (100,) if args.quick else tuple(SETTINGS)
    repeats = 1 if args.quick else args.repeats
    with tempfile.TemporaryDirectory() as tmp:
        old = Path(tmp) / "baseline"
        subprocess.run(["git", "worktree", "add", "--detach", str(old), args.baseline],
                       cwd=ROOT, check=True, capture_output=True)  # fmt: skip
        try:
            print(f"| M | grid | {args.baseline} steps/s | this tree steps/s | ratio |")
            print("|---:|---|---:|---:|---:|")
            for m in robots:
                runs: dict[str, list[float]] = {"old": [], "new": []}
                for _ in range(repeats):
                    runs["old"].append(measure(old, m, args.decisions))
                    runs["new"].append(measure(ROOT, m, args.decisions))
                med = {k: statistics.median(v) for k, v in runs.items()}
                spread = {k: f"{min(v):,.0f}-{max(v):,.0f}" for k, v in runs.items()}
                side = SETTINGS[m]
                print(f"| {m:,} | open {side}x{side} | {med['old']:,.0f} ({spread['old']}) | "
                      f"{med['new']:,.0f} ({spread['new']}) | {med['new'] / med['old']:.2f}x |",
                      flush=True)  # fmt: skip
        finally:
            subprocess.run(["git", "worktree", "remove", "--force", str(old)], cwd=ROOT,
                           check=False, capture_output=True)  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())
