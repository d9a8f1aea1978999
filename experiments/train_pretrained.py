"""Train the shipped pretrained RTAW policies and copy them into the package.

Usage::

    python experiments/train_pretrained.py                 # every entry of the registry
    python experiments/train_pretrained.py A_astar_m10     # selected entries
    python experiments/train_pretrained.py --jobs 2 --plus # every RTAW+ entry, 2 at a time
    python experiments/train_pretrained.py --summary       # the shipped policies' figures

    # The entries (default: all) as one `rtaw-train -m` sweep on a Hydra launcher:
    python experiments/train_pretrained.py --launcher joblib
    python experiments/train_pretrained.py --launcher ray --set hydra.launcher.ray.init.address=auto
    python experiments/train_pretrained.py --launcher submitit_slurm \
        --set hydra.launcher.partition=cpu --set hydra.launcher.cpus_per_task=4
    python experiments/train_pretrained.py --launcher ray --print   # print the command only

Each entry of ``rtaw_marl/policies/pretrained/registry.py`` names its ``rtaw-train`` overrides;
this script runs exactly that command, then writes the best checkpoint, without the
optimizer state (a few KB), to ``rtaw_marl/policies/pretrained/<name>.pt``. The checkpoint keeps
the command line that trained it.

Curriculum entries (``CURRICULUM`` in the registry: Table II's 500-robot RTAW+) continue
the best checkpoint of a 100-robot run in ``runs/pretrained/<base>``; continued entries
(``CONTINUED``: Table I's RTAW+ at three times the budget) continue a copy of that run
from its ``last.pt``. Both run after every other entry, and ``--launcher`` leaves them
out.

With ``--launcher`` the entries run as one Hydra sweep, ``rtaw-train -m +zoo=<names>``
(each entry is an option of the ``zoo`` config group, built from the registry), on the
joblib, Ray or Slurm (submitit) launcher; each job trains into
``runs/pretrained/sweep/<name>``, and the checkpoints are shipped when the sweep ends
(docs/cluster.md).
"""

from __future__ import annotations

import argparse
import shlex
import shutil
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

from rtaw_marl.models.checkpoint import load_checkpoint, save_checkpoint
from rtaw_marl.policies.pretrained.registry import (
    CONTINUED,
    CURRICULUM,
    PRETRAINED,
    train_command,
)

ROOT = Path(__file__).resolve().parents[1]
SHIPPED = ROOT / "rtaw_marl" / "policies" / "pretrained"
SWEEP_DIR = ROOT / "runs" / "pretrained" / "sweep"
LAUNCHERS = ("basic", "joblib", "ray", "submitit_local", "submitit_slurm")
#: Entries that continue another entry's run in ``runs/pretrained/<base>``.
STAGED = {*CURRICULUM, *CONTINUED}


def train_one(name: str) -> str:
    """Train entry ``name`` (from scratch, or from a copy of its base's run) and ship its
    best checkpoint; returns a summary."""
    run_dir = ROOT / "runs" / "pretrained" / name
    shutil.rmtree(run_dir, ignore_errors=True)
    if name in CONTINUED:
        shutil.copytree(ROOT / "runs" / "pretrained" / CONTINUED[name], run_dir)
    cmd = train_command(name, run_dir)
    print(" ".join(cmd), flush=True)
    log = ROOT / "runs" / "pretrained" / f"{name}.log"
    log.parent.mkdir(parents=True, exist_ok=True)
    with log.open("w") as fh:
        subprocess.run(cmd, check=True, cwd=ROOT, stdout=fh, stderr=subprocess.STDOUT)
    return ship(name, run_dir, cmd)


def sweep_command(names: list[str], launcher: str, settings: list[str]) -> list[str]:
    """``rtaw-train -m +zoo=<names>`` on ``launcher``: one job folder per entry."""
    exe = str(Path(sys.executable).with_name("rtaw-train"))
    return [
        exe, "--multirun", f"+zoo={','.join(names)}", f"hydra/launcher={launcher}",
        f"hydra.sweep.dir={SWEEP_DIR}", "hydra.sweep.subdir=${hydra:runtime.choices.zoo}",
        "progress=false", *settings,
    ]  # fmt: skip


def ship(name: str, run_dir: Path, cmd: list[str]) -> str:
    """Write the best checkpoint of ``run_dir`` into the package; returns a summary."""
    ckpt = load_checkpoint(run_dir / "checkpoints" / "best.pt")
    ckpt.pop("optimizer", None)
    ckpt["command"] = cmd
    payload = {k: v for k, v in ckpt.items() if k not in ("format", "features", "versions")}
    out = save_checkpoint(SHIPPED / f"{name}.pt", payload)
    curve = ROOT / "docs" / "img" / f"training_{name}.png"
    curve.parent.mkdir(parents=True, exist_ok=True)
    shutil.copyfile(run_dir / "training_curve.png", curve)
    row = ckpt["eval"]
    return (
        f"{name}: best selection TTD {row['ttd']:.1f} (MPDM {row['mpdm_ttd']:.1f}, "
        f"lookahead {row.get('lookahead_ttd', float('nan')):.1f}) at {ckpt['frames']} frames "
        f"-> {out}"
    )


def summary() -> str:
    """A markdown table of the shipped policies' selection figures, from their checkpoints."""
    lines = [
        "| policy | model | frames (best / run) | selection TTD | MPDM | lookahead | vs MPDM "
        "| vs lookahead | curve |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for name in PRETRAINED:
        path = SHIPPED / f"{name}.pt"
        if not path.is_file():
            continue
        ckpt = load_checkpoint(path)
        best = ckpt["eval"]
        look = best.get("lookahead_ttd", float("nan"))
        # The run's budget from its recipe: a continued run may select its base's best,
        # whose config still says the base's frames.
        run = int(next(o for o in PRETRAINED[name] if o.startswith("frames=")).split("=")[1])
        lines.append(
            f"| {name} | {ckpt['config']['model'].get('name', 'rtaw')} | {ckpt['frames']:,} / "
            f"{run:,} | {best['ttd']:.0f} | {best['mpdm_ttd']:.0f} | "
            f"{look:.0f} | {100 * (1 - best['ttd'] / best['mpdm_ttd']):+.1f}% | "
            f"{100 * (1 - best['ttd'] / look):+.1f}% | [png](img/training_{name}.png) |"
        )
    return "\n".join(lines)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("names", nargs="*", help="registry entries (default: all)")
    parser.add_argument("--jobs", type=int, default=1, help="training runs at once")
    parser.add_argument("--plus", action="store_true", help="only the RTAW+ entries")
    parser.add_argument("--paper", action="store_true", help="only the paper-network entries")
    parser.add_argument("--summary", action="store_true", help="print the shipped policies' table")
    parser.add_argument(
        "--launcher", choices=LAUNCHERS, help="train the entries as one rtaw-train -m sweep"
    )
    parser.add_argument(
        "--set", action="append", default=[], metavar="KEY=VALUE",
        help="an extra override of the sweep (hydra.launcher.*, collector.*), repeatable",
    )  # fmt: skip
    parser.add_argument("--print", action="store_true", help="print the sweep command only")
    args = parser.parse_args()
    if args.summary:
        print(summary())
        return 0
    names = args.names or [
        n for n in PRETRAINED
        if not (args.plus and not n.endswith("_plus")) and not (args.paper and n.endswith("_plus"))
    ]  # fmt: skip
    if args.launcher:
        later = [n for n in names if n in STAGED]
        if later:
            # They continue a base run in runs/pretrained/<base>, not in the sweep folder.
            print(
                f"note: left out of the sweep (curriculum and continued entries; train "
                f"them without --launcher once their base is trained): {', '.join(later)}",
                flush=True,
            )
            names = [n for n in names if n not in STAGED]
        cmd = sweep_command(names, args.launcher, args.set)
        print(shlex.join(cmd), flush=True)
        if args.print:
            return 0
        shutil.rmtree(SWEEP_DIR, ignore_errors=True)
        subprocess.run(cmd, check=True, cwd=ROOT)
        for name in names:
            print(ship(name, SWEEP_DIR / name, cmd), flush=True)
        return 0
    # Staged entries continue their base's run: they start once every base is done.
    for phase in ([n for n in names if n not in STAGED], [n for n in names if n in STAGED]):
        with ThreadPoolExecutor(max_workers=args.jobs) as pool:
            for line in pool.map(train_one, phase):
                print(line, flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
