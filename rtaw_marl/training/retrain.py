"""Retrain zoo entries and ship their best checkpoints (what ``rtaw-zoo`` runs).

Each entry trains with its recipe's exact command (:func:`rtaw_marl.training.zoo.
train_command`) into ``<runs>/<name>`` (``runs/pretrained/<name>``), as a subprocess
whose output goes to ``<runs>/<name>.log``; then :func:`ship` writes its best checkpoint,
without the optimizer state (a few KB), to ``<ship_to>/<name>.pt`` (by default the
package's ``policies/pretrained/`` folder) and copies its training curve. A continued
entry first copies its base's run folder and resumes its ``last.pt``; a curriculum entry
continues its base's ``best.pt``: both run after every other entry, and need their
base's run (trained in the same call, or before). :func:`sweep_command` runs the
``train`` entries as one ``rtaw-train -m +zoo=...`` sweep on a Hydra launcher instead.
"""

from __future__ import annotations

import json
import shutil
import subprocess
from collections.abc import Iterable, Sequence
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

from rtaw_marl.errors import ConfigError, unknown_name
from rtaw_marl.models.checkpoint import load_checkpoint, save_checkpoint
from rtaw_marl.policies.pretrained.registry import SHIPPED
from rtaw_marl.training.config import upgrade_config
from rtaw_marl.training.zoo import RUNS, ZOO, recipe, rtaw_train, train_command
from rtaw_marl.utils.atomic import atomic_write

__all__ = [
    "LAUNCHERS",
    "SHIPPED",
    "check_bases",
    "phases",
    "reselect",
    "select",
    "ship",
    "summary",
    "sweep_command",
    "train_entries",
    "train_entry",
    "train_sweep",
]

#: Hydra launchers a zoo sweep may run on (``hydra/launcher=...``).
LAUNCHERS = ("basic", "joblib", "ray", "submitit_local", "submitit_slurm")


def select(names: Sequence[str], plus: bool = False, paper: bool = False) -> list[str]:
    """``names`` checked against the zoo, or every entry (only RTAW+ with ``plus``, only
    the paper's network with ``paper``).

    Raises:
        ConfigError: An unknown name.
    """
    for name in names:
        recipe(name)
    if names:
        return list(names)
    return [n for n in ZOO if not (plus and ZOO[n].model != "rtaw_plus") and not (
        paper and ZOO[n].model == "rtaw_plus")]  # fmt: skip


def phases(names: Iterable[str]) -> tuple[list[str], list[str]]:
    """``names`` split into ``train`` entries and the staged ones that continue them."""
    names = list(names)
    return [n for n in names if ZOO[n].stage == "train"], [
        n for n in names if ZOO[n].stage != "train"
    ]


def _base_run(name: str, runs: Path) -> Path:
    """What a staged entry continues: its base's run folder (continued) or best
    checkpoint (curriculum)."""
    entry = ZOO[name]
    folder = runs / str(entry.base)
    return folder if entry.stage == "continued" else folder / "checkpoints" / "best.pt"


def check_bases(names: Iterable[str], runs: Path = RUNS) -> None:
    """Every staged entry's base is trained in this call or already in ``runs``.

    Raises:
        ConfigError: A base run is missing (the message names the command that trains it).
    """
    names = set(names)
    for name in sorted(names):
        entry = ZOO[name]
        # A generalist or a LoRR entry starts from its base's shipped checkpoint, not
        # from a run.
        shipped = entry.stage in ("generalist", "lorr")
        if entry.base is None or shipped or entry.base in names or _base_run(name, runs).exists():
            continue
        raise ConfigError(
            f"{name} continues {entry.base}, but {_base_run(name, runs)} is missing: "
            f"train it first with rtaw-zoo {entry.base}"
        )


def train_entry(
    name: str, runs: Path = RUNS, ship_to: Path = SHIPPED, curves: Path | None = None
) -> str:
    """Train entry ``name`` into ``<runs>/<name>`` (from scratch, or from a copy of its
    base's run) and ship its best checkpoint; returns a summary line.

    Raises:
        subprocess.CalledProcessError: ``rtaw-train`` failed (its log is beside the run).
    """
    run_dir = runs / name
    shutil.rmtree(run_dir, ignore_errors=True)
    if ZOO[name].stage == "continued":
        shutil.copytree(_base_run(name, runs), run_dir)
    cmd = train_command(name, run_dir, runs)
    print(" ".join(cmd), flush=True)
    log = runs / f"{name}.log"
    log.parent.mkdir(parents=True, exist_ok=True)
    with log.open("w") as fh:
        subprocess.run(cmd, check=True, stdout=fh, stderr=subprocess.STDOUT)
    if ZOO[name].second_stage:
        return reselect(name, runs, ship_to, curves)
    return ship(name, run_dir, cmd, ship_to, curves)


def reselect(
    name: str,
    runs: Path = RUNS,
    ship_to: Path = SHIPPED,
    curves: Path | None = None,
    workers: int = 1,
) -> str:
    """Run entry ``name``'s second selection stage on its finished run and ship the
    candidate it picks (the checkpoint records the stage's gains); returns a summary.

    Raises:
        ConfigError: The entry has no second stage, or its run is missing.
    """
    from rtaw_marl.training.selection import run_candidates, second_stage

    entry, run_dir = ZOO[name], runs / name
    if not entry.second_stage:
        raise ConfigError(f"zoo entry {name!r} has no second selection stage")
    candidates = run_candidates(run_dir)
    stored = load_checkpoint(run_dir / "checkpoints" / "best.pt")["config"]
    first = upgrade_config(stored)["selection"]["seeds"]  # "eval" in older runs
    result = second_stage(candidates, entry.second_stage, first_stage=first, workers=workers)
    for label, gain in result.gains.items():
        # A pooled difference is in percent already (its mean, low and high).
        interval = f"[{gain.low:+.2f}, {gain.high:+.2f}]"
        print(f"{name} second stage: {label} {gain.mean:+.2f}% {interval} vs "
              f"{result.reference} (n = {gain.n})", flush=True)  # fmt: skip
    record = {**result.as_dict(), "ttd": result.ttd}
    text = json.dumps(record, indent=1).encode()
    atomic_write(run_dir / "second_stage.json", lambda fh: fh.write(text))
    cmd = train_command(name, run_dir, runs)
    return ship(name, run_dir, cmd, ship_to, curves, candidates[result.chosen], result.as_dict())


def train_entries(
    names: Sequence[str],
    jobs: int = 1,
    runs: Path = RUNS,
    ship_to: Path = SHIPPED,
    curves: Path | None = None,
) -> list[str]:
    """Train ``names``, ``jobs`` at a time: the ``train`` entries, then the staged ones
    (they continue a base's run). Returns the summary lines."""
    check_bases(names, runs)
    lines = []
    for phase in phases(names):
        with ThreadPoolExecutor(max_workers=max(1, jobs)) as pool:
            for line in pool.map(lambda n: train_entry(n, runs, ship_to, curves), phase):
                print(line, flush=True)
                lines.append(line)
    return lines


def sweep_command(names: Sequence[str], launcher: str, settings: Sequence[str] = (),
                  runs: Path = RUNS) -> list[str]:  # fmt: skip
    """``rtaw-train -m +zoo=<names>`` on ``launcher``: each job in ``<runs>/sweep/<name>``.

    Raises:
        ConfigError: No names, an unknown launcher, or a staged entry (it continues a run in
            ``<runs>/<base>``, not in the sweep's folder).
    """
    if launcher not in LAUNCHERS:
        raise unknown_name("launcher", launcher, list(LAUNCHERS))
    if not names:
        raise ConfigError("no zoo entry to sweep")
    staged = phases(names)[1]
    if staged:
        raise ConfigError(f"staged entries cannot run in a sweep: {', '.join(staged)}")
    return [
        rtaw_train(), "--multirun", f"+zoo={','.join(names)}", f"hydra/launcher={launcher}",
        f"hydra.sweep.dir={(runs / 'sweep').resolve()}",
        "hydra.sweep.subdir=${hydra:runtime.choices.zoo}", "progress=false", *settings,
    ]  # fmt: skip


def ship(
    name: str,
    run_dir: Path,
    cmd: list[str],
    ship_to: Path = SHIPPED,
    curves: Path | None = None,
    source: Path | None = None,
    selection: dict | None = None,
) -> str:
    """Write the best checkpoint of ``run_dir`` (or ``source``, a second stage's pick,
    recording ``selection``) to ``<ship_to>/<name>.pt`` (recording ``cmd``) and its
    training curve to ``<curves>/training_<name>.png``; returns a summary line."""
    ckpt = load_checkpoint(source or run_dir / "checkpoints" / "best.pt")
    ckpt.pop("optimizer", None)
    ckpt["command"] = cmd
    if selection is not None:
        ckpt["selection"] = selection
    payload = {k: v for k, v in ckpt.items() if k not in ("format", "features", "versions")}
    out = save_checkpoint(ship_to / f"{name}.pt", payload)
    curve = run_dir / "training_curve.png"
    if curves is not None and curve.is_file():
        curves.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(curve, curves / f"training_{name}.png")
    row = ckpt["eval"]
    return (
        f"{name}: best selection TTD {row['ttd']:.1f} (MPDM {row['mpdm_ttd']:.1f}, "
        f"lookahead {row.get('lookahead_ttd', float('nan')):.1f}) at {ckpt['frames']} frames "
        f"-> {out}"
    )


def summary(shipped: Path = SHIPPED) -> str:
    """A markdown table of the shipped policies' selection figures, from their checkpoints
    (docs/training.md's zoo table): the entries selected on TTD (not the ``lorr`` ones)."""
    lines = [
        "| policy | model | frames (best / run) | selection TTD | MPDM | lookahead | vs MPDM "
        "| vs lookahead | curve |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for name, entry in ZOO.items():
        path = shipped / f"{name}.pt"
        # LoRR entries select on tasks finished, not TTD (docs/training.md gives theirs).
        if not path.is_file() or entry.stage == "lorr":
            continue
        ckpt = load_checkpoint(path)
        best = ckpt["eval"]
        look = best.get("lookahead_ttd", float("nan"))
        # The run's budget from its recipe: a continued run may select its base's best,
        # whose config still says the base's frames.
        lines.append(
            f"| {name} | {ckpt['config']['model'].get('name', 'rtaw')} | {ckpt['frames']:,} / "
            f"{entry.budget:,} | {best['ttd']:.0f} | {best['mpdm_ttd']:.0f} | "
            f"{look:.0f} | {100 * (1 - best['ttd'] / best['mpdm_ttd']):+.1f}% | "
            f"{100 * (1 - best['ttd'] / look):+.1f}% | [png](img/training_{name}.png) |"
        )
    return "\n".join(lines)


def train_sweep(
    names: Sequence[str],
    launcher: str,
    settings: Sequence[str] = (),
    runs: Path = RUNS,
    ship_to: Path = SHIPPED,
    curves: Path | None = None,
) -> list[str]:
    """Run :func:`sweep_command`, then ship each job's best checkpoint; returns the
    summary lines."""
    cmd = sweep_command(names, launcher, settings, runs)
    shutil.rmtree(runs / "sweep", ignore_errors=True)
    subprocess.run(cmd, check=True)
    lines = [ship(name, runs / "sweep" / name, cmd, ship_to, curves) for name in names]
    for line in lines:
        print(line, flush=True)
    return lines
