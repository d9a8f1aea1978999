"""The paper's reward ablation: RTAW trained with each reward, evaluated on TTD and makespan.

Usage::

    python -m benchmarks.scripts.reward_ablation            # train the three policies, then evaluate
    python -m benchmarks.scripts.reward_ablation --eval     # evaluate existing runs only

Trains ``sim.reward=ttd|length|ttd_length`` on layout A with A*, 10 robots, designated
tasks (``algo=ppo_fast``, 102,400 frames, seed 0;
:func:`benchmarks.variants.reward_command`) into ``runs/ablation/<reward>``, then
evaluates each best checkpoint with the TTD reward's environment (the reward does not
change the dynamics) on the evaluation seeds in ``drain`` mode beside MPDM, and
rewrites the ``ablation`` section of docs/results.md.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from benchmarks.study import replace_section
from benchmarks.tables import vs
from benchmarks.variants import REWARDS, reward_command, run_logged
from rtaw_marl.evaluation import evaluate
from rtaw_marl.evaluation.report import markdown_table
from rtaw_marl.policies import make_baseline
from rtaw_marl.policies.network import load_policy
from rtaw_marl.scenarios import SCENARIOS
from rtaw_marl.sim.builder import build_sim

ROOT = Path(__file__).resolve().parents[2]
RUNS = ROOT / "runs" / "ablation"
SEEDS = list(range(20))  # the evaluation seeds


def train(reward: str) -> Path:
    """Train with ``reward`` unless its run is there; returns the run folder."""
    run_dir = RUNS / reward
    if not (run_dir / "checkpoints" / "best.pt").is_file():
        run_logged(reward_command(reward, run_dir), run_dir.with_suffix(".log"))
    return run_dir


def table(runs: dict[str, Path]) -> str:
    """Mean TTD and makespan of MPDM and each run, and each run's TTD against MPDM's."""
    sim = build_sim(SCENARIOS["A_astar_m10"].spec())
    policies = {"MPDM": make_baseline("mpdm", env=sim)}
    policies.update(
        {f"RTAW, reward={r}": load_policy(p / "checkpoints" / "best.pt") for r, p in runs.items()}
    )
    res = evaluate(sim, policies, SEEDS)
    mpdm = res["MPDM"]["ttd"]
    rows = [
        [name, f"{np.mean(m['ttd']):.0f}", f"{np.mean(m['makespan']):.0f}",
         vs(mpdm, m["ttd"]) if name != "MPDM" else "-"]
        for name, m in res.items()
    ]  # fmt: skip
    return markdown_table(["policy", "TTD", "makespan", "TTD vs MPDM (paired, 95% CI)"], rows)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--eval", action="store_true", help="evaluate existing runs only")
    args = parser.parse_args()
    runs = {r: RUNS / r for r in REWARDS} if args.eval else {r: train(r) for r in REWARDS}
    body = table(runs)
    print(body)
    replace_section(ROOT / "docs" / "results.md", "ablation", body)
    return 0


if __name__ == "__main__":
    sys.exit(main())
