"""The paper's reward ablation: RTAW trained with each reward, evaluated on TTD and makespan.

Usage::

    python experiments/reward_ablation.py            # train the three policies, then evaluate
    python experiments/reward_ablation.py --eval     # evaluate existing runs only

Trains ``env.reward=ttd|length|ttd_length`` on layout A with A*, 10 robots, designated
tasks (``algo=ppo_fast``, 102,400 frames, seed 0) into ``runs/ablation/<reward>``, then
evaluates each best checkpoint with the TTD reward's environment (the reward does not
change the dynamics) on seeds 0-4 in ``drain`` mode beside MPDM, and rewrites the
``ablation`` section of docs/results.md.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
from pathlib import Path

import numpy as np

from rtaw_marl.evaluation import evaluate
from rtaw_marl.policies import make_baseline
from rtaw_marl.policies.network import load_policy
from rtaw_marl.sim.builder import SimSpec

sys.path.insert(0, str(Path(__file__).resolve().parent))
from paper_tables import replace_section, vs

ROOT = Path(__file__).resolve().parents[1]
REWARDS = ("ttd", "length", "ttd_length")
SEEDS = list(range(20))  # the evaluation seeds
COMMON = ["layout=A", "navigator=astar", "env.num_robots=10", "algo=ppo_fast",
          "frames=102400", "eval.every_frames=10240", "seed=0", "progress=false"]  # fmt: skip


def train(reward: str) -> Path:
    run_dir = ROOT / "runs" / "ablation" / reward
    if (run_dir / "checkpoints" / "best.pt").is_file():
        return run_dir
    exe = str(Path(sys.executable).with_name("rtaw-train"))
    cmd = [exe, *COMMON, f"env.reward={reward}", f"output_dir={run_dir}"]
    print(" ".join(cmd), flush=True)
    subprocess.run(cmd, check=True, cwd=ROOT)
    return run_dir


def table(runs: dict[str, Path]) -> str:
    sim = SimSpec.of({"num_robots": 10, "num_tasks": 500}, {"name": "preset", "preset": "A"},
                    "astar", "designated").build()  # fmt: skip
    policies = {"MPDM": make_baseline("mpdm")}
    policies.update(
        {f"RTAW, reward={r}": load_policy(p / "checkpoints" / "best.pt") for r, p in runs.items()}
    )
    res = evaluate(sim, policies, SEEDS)
    mpdm = res["MPDM"]["ttd"]
    lines = ["| policy | TTD | makespan | TTD vs MPDM (paired, 95% CI) |", "|---|---|---|---|"]
    for name, metrics in res.items():
        lines.append(
            f"| {name} | {np.mean(metrics['ttd']):.0f} | {np.mean(metrics['makespan']):.0f} "
            f"| {vs(mpdm, metrics['ttd']) if name != 'MPDM' else '-'} |"
        )
        print(lines[-1], flush=True)
    return "\n".join(lines)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--eval", action="store_true", help="evaluate existing runs only")
    args = parser.parse_args()
    runs = (
        {r: ROOT / "runs" / "ablation" / r for r in REWARDS}
        if args.eval
        else {r: train(r) for r in REWARDS}
    )
    replace_section("ablation", table(runs))
    return 0


if __name__ == "__main__":
    sys.exit(main())
