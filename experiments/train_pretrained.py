"""Train the shipped pretrained RTAW policies and copy them into the package.

Usage::

    python experiments/train_pretrained.py                 # every entry of the registry
    python experiments/train_pretrained.py A_astar_m10     # selected entries

Each entry of ``rtaw_marl/policies/pretrained/registry.py`` names its ``rtaw-train`` overrides;
this script runs exactly that command, then writes the best checkpoint, without the
optimizer state (a few KB), to ``rtaw_marl/policies/pretrained/<name>.pt``. The checkpoint keeps
the command line that trained it.
"""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

from rtaw_marl.models.checkpoint import load_checkpoint, save_checkpoint
from rtaw_marl.policies.pretrained.registry import PRETRAINED, train_command

ROOT = Path(__file__).resolve().parents[1]


def main(names: list[str]) -> int:
    for name in names or list(PRETRAINED):
        run_dir = ROOT / "runs" / "pretrained" / name
        shutil.rmtree(run_dir, ignore_errors=True)
        cmd = train_command(name, run_dir)
        print(" ".join(cmd), flush=True)
        subprocess.run(cmd, check=True, cwd=ROOT)
        ckpt = load_checkpoint(run_dir / "checkpoints" / "best.pt")
        ckpt.pop("optimizer", None)
        ckpt["command"] = cmd
        out = ROOT / "rtaw_marl" / "pretrained" / f"{name}.pt"
        payload = {k: v for k, v in ckpt.items() if k not in ("format", "features", "versions")}
        save_checkpoint(out, payload)
        curve = ROOT / "docs" / "img" / f"training_{name}.png"
        curve.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(run_dir / "training_curve.png", curve)
        print(f"{name}: best eval TTD {ckpt['eval']['ttd']:.1f} -> {out}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
