"""Greedy TTD against frames and wall time for PPO configurations, on the same seeds.

Each configuration is one ``rtaw-train`` run (as a subprocess, so nothing is shared)
on the default scenario; its evaluation history (greedy TTD on the selection seeds
1000-1009 against MPDM on the same seeds) is read from the checkpoint and written to
``benchmarks/data/train_curves.json``; ``--plot`` draws docs/img/train_curves.png with the
y-axis scaled to the baselines. Runs that already finished are reused (``runs/curves``).

Usage::

    python -m benchmarks.scripts.train_curves default paper zoo_recipe   # docs/training.md
    python -m benchmarks.scripts.train_curves --plot
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
from pathlib import Path

from rtaw_marl.models.checkpoint import load_checkpoint
from rtaw_marl.training.zoo import rtaw_train

ROOT = Path(__file__).resolve().parents[2]
RUNS = ROOT / "runs" / "curves"
DATA = ROOT / "benchmarks" / "data" / "train_curves.json"
IMG = ROOT / "docs" / "img" / "train_curves.png"

#: name -> rtaw-train overrides.
CONFIGS: dict[str, list[str]] = {
    # The throughput-tuned default, with the paper's 4M-frame budget.
    "default": ["frames=4005888"],
    # The paper's hyperparameter table, at the shipped policies' budget.
    "paper": ["algo=ppo_paper", "frames=102400", "selection.every_frames=10240"],
    # The recipe of the shipped 102,400-frame policies (policy coefficient 1.0).
    "zoo_recipe": ["algo=ppo_fast", "frames=102400", "selection.every_frames=10240",
                   "collector.envs_per_worker=16"],
}  # fmt: skip


def run(name: str) -> dict:
    out = RUNS / name
    last = out / "checkpoints" / "last.pt"
    if not last.is_file():
        cmd = [rtaw_train(), *CONFIGS[name], f"output_dir={out}", "progress=false"]
        print(" ".join(cmd), flush=True)
        subprocess.run(cmd, check=True, cwd=ROOT)
    ckpt = load_checkpoint(last)
    return {"overrides": CONFIGS[name], "history": ckpt["history"]}


def plot(data: dict, path: Path) -> None:
    """Greedy TTD against frames and against wall time, y scaled to the baselines."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(11, 3.8), dpi=110, sharey=True)
    mpdm = next(iter(data.values()))["history"][0]["mpdm_ttd"]
    for name, run in data.items():
        rows = run["history"][1:]  # the untrained start (frame 0) is off the scale anyway
        for ax, key in zip(axes, ("frames", "wall_s"), strict=True):
            ax.plot([r[key] for r in rows], [r["ttd"] for r in rows], marker=".", label=name)
    for ax, label in zip(axes, ("frames (decisions)", "wall time (s)"), strict=True):
        ax.axhline(mpdm, color="tab:red", linestyle="--", label="MPDM")
        ax.set_xscale("log")
        ax.set_xlabel(label)
    # The baselines sit within a few percent of each other: scale to them, not to the
    # untrained start (about 3x MPDM's TTD).
    axes[0].set_ylim(0.9 * mpdm, 1.1 * mpdm)
    axes[0].set_ylabel("greedy TTD, selection seeds 1000-1009")
    axes[1].legend(fontsize=8)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path)
    plt.close(fig)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("names", nargs="*", choices=[*CONFIGS, []])
    parser.add_argument("--plot", action="store_true")
    args = parser.parse_args()
    data = json.loads(DATA.read_text()) if DATA.is_file() else {}
    for name in args.names:
        data[name] = run(name)
        DATA.parent.mkdir(parents=True, exist_ok=True)
        DATA.write_text(json.dumps(data, indent=1) + "\n")
        best = min(r["ttd"] for r in data[name]["history"])
        print(f"{name}: best selection TTD {best:.1f}", flush=True)
    if args.plot:
        plot(data, IMG)
        print(f"wrote {IMG}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
