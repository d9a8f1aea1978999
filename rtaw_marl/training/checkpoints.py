"""A training run on disk: its checkpoints, and resuming it without losing or repeating
anything.

``last.pt`` is written after every evaluation (and on Ctrl-C), ``best.pt`` when the
evaluation is the best yet, ``best.pt`` first: a kill between the two writes leaves a
``last.pt`` that never claims a best its folder lacks. Both writes are atomic
(:func:`~rtaw_marl.models.checkpoint.save_checkpoint`).

Resuming refuses what would silently mix two runs: a checkpoint of another model or
scenario (unless ``resume_new_scenario=true``), or a ``frames`` budget it has already
spent. It removes the temporary files of a write that a kill interrupted, and cuts
the CSV logs back to the checkpoint, so the rows a killed run wrote after its last
checkpoint are not followed by the same steps again.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import torch

from rtaw_marl.errors import ConfigError
from rtaw_marl.models.checkpoint import Actor, Critic, load_checkpoint, plain_model, save_checkpoint
from rtaw_marl.training.config import TrainConfig
from rtaw_marl.utils.atomic import atomic_write
from rtaw_marl.utils.plain import as_plain

__all__ = ["Checkpoints", "Progress", "clean_interrupted_writes", "resume", "trim_csv_logs"]

#: The config groups that define what a run is evaluated on.
SCENARIO_KEYS = ("env", "layout", "navigator", "tasks")


@dataclass
class Progress:
    """Where a run stands (restored on resume)."""

    frames: int = 0
    iteration: int = 0
    best_ttd: float = float("inf")


class Checkpoints:
    """``best.pt`` when an evaluation is the best yet, then ``last.pt``.

    Args:
        cfg: The run's config (stored in every checkpoint).
        folder: ``<run_dir>/checkpoints``.
        nets: The actor and critic networks.
        optim: Their optimizer.
        progress: The run's progress (frames, iteration, best TTD).
    """

    def __init__(
        self,
        cfg: TrainConfig,
        folder: Path,
        nets: tuple[Actor, Critic],
        optim: torch.optim.Optimizer,
        progress: Progress,
    ) -> None:
        self.cfg, self.nets, self.optim, self.progress = cfg, nets, optim, progress
        self.last, self.best = folder / "last.pt", folder / "best.pt"

    def save(self, row: dict[str, float], history: list[dict[str, float]]) -> None:
        """Write the checkpoints after the evaluation ``row``, with every evaluation so
        far (so a resumed run draws its whole curve)."""
        payload = self._payload(row, history)
        if row["ttd"] <= self.progress.best_ttd:
            save_checkpoint(self.best, payload)
        save_checkpoint(self.last, payload)

    def save_last(self, history: list[dict[str, float]]) -> Path | None:
        """Write ``last.pt`` between evaluations (on Ctrl-C); ``None`` before the first
        evaluation, when there is no row to store."""
        if not history:
            return None
        return save_checkpoint(self.last, self._payload(history[-1], history))

    def _payload(self, row: dict[str, float], history: list[dict[str, float]]) -> dict[str, Any]:
        actor, critic = self.nets
        progress = self.progress
        return {
            "model": {"actor": actor.state_dict(), "critic": critic.state_dict()},
            "model_config": plain_model(self.cfg.model),
            "optimizer": self.optim.state_dict(),
            "config": as_plain(self.cfg),
            "frames": progress.frames,
            "iteration": progress.iteration,
            "best_ttd": progress.best_ttd,
            "eval": row,
            "history": list(history),
        }


def resume(
    cfg: TrainConfig,
    nets: tuple[Actor, Critic],
    optim: torch.optim.Optimizer,
    run_dir: Path,
) -> tuple[Progress, list[dict[str, float]]]:
    """Load ``cfg.resume`` into the networks and optimizer; returns the progress and the
    evaluation history to continue from.

    Raises:
        ConfigError: The checkpoint is of another model, of another scenario (without
            ``resume_new_scenario``), holds no optimizer state (a shipped policy), or
            already holds ``frames`` frames.
    """
    path = Path(cfg.resume)
    ckpt = load_checkpoint(path)
    model_cfg = plain_model(cfg.model)
    if plain_model(ckpt["model_config"]) != model_cfg:
        raise ConfigError(
            f"resume: checkpoint model {ckpt['model_config']} differs from model {model_cfg}"
        )
    if "optimizer" not in ckpt:
        raise ConfigError(
            f"resume: {path} holds a policy's weights but no optimizer state (a shipped "
            "policy is stripped); resume from a run's checkpoints/last.pt or best.pt"
        )
    frames = int(ckpt["frames"])
    if cfg.frames <= frames:
        raise ConfigError(
            f"resume: the checkpoint has already trained {frames} frames; "
            f"frames={cfg.frames} must be larger to train on"
        )
    for net, name in zip(nets, ("actor", "critic"), strict=True):
        net.load_state_dict(ckpt["model"][name])
    optim.load_state_dict(ckpt["optimizer"])
    progress = Progress(frames, int(ckpt["iteration"]), float(ckpt.get("best_ttd", float("inf"))))
    history = list(ckpt.get("history", []))
    changes = scenario_changes(ckpt.get("config", {}), as_plain(cfg))
    if changes and not cfg.resume_new_scenario:
        raise ConfigError(
            f"resume: {path} was trained on another scenario ({'; '.join(changes[:3])}); "
            "its best TTD does not compare. Pass resume_new_scenario=true to continue "
            "training it here with a fresh best"
        )
    best = run_dir / "checkpoints" / "best.pt"
    if changes:
        progress.best_ttd, history = float("inf"), []
    elif not best.exists() and (path.parent / "best.pt").is_file():
        # Resumed into a new folder: bring the best along, or best.pt would be missing
        # until a later evaluation beats it.
        source = path.parent / "best.pt"
        atomic_write(best, lambda fh: fh.write(source.read_bytes()))
    elif not best.exists():
        progress.best_ttd = float("inf")
    torch.manual_seed(cfg.seed + progress.iteration)
    return progress, history


def scenario_changes(old: dict[str, Any], new: dict[str, Any]) -> list[str]:
    """``["env.num_robots: 10 -> 100", ...]``: where two runs' scenarios differ (the
    groups of :data:`SCENARIO_KEYS` and the evaluation seeds)."""
    changes = []
    for group in SCENARIO_KEYS:
        a, b = old.get(group, {}), new.get(group, {})
        for key in sorted(set(a) | set(b)):
            if a.get(key) != b.get(key):
                changes.append(f"{group}.{key}: {a.get(key)!r} -> {b.get(key)!r}")
    a, b = old.get("eval", {}).get("seeds"), new.get("eval", {}).get("seeds")
    if a != b:
        changes.append(f"eval.seeds: {a} -> {b}")
    return changes


def clean_interrupted_writes(folder: Path) -> list[Path]:
    """Remove the temporary files that killed checkpoint writes left (``.last.pt.*.tmp``);
    safe because the run holds its folder. Returns what was removed."""
    stale = sorted(folder.glob(".*.pt.*.tmp")) if folder.is_dir() else []
    for tmp in stale:
        tmp.unlink(missing_ok=True)
    return stale


def trim_csv_logs(logs: Path, frames: int) -> int:
    """Drop the CSV rows logged after ``frames`` (a killed run's last steps, which the
    resumed run logs again); returns how many rows were dropped.

    The ``imitation`` scalars are kept: their step axis counts teacher decisions, not
    frames, and they were all logged before the first checkpoint.
    """
    dropped = 0
    for csv in sorted(logs.rglob("*.csv")) if logs.is_dir() else []:
        if "imitation" in csv.relative_to(logs).parts:
            continue
        lines = csv.read_text().splitlines(keepends=True)
        # A line without its newline is one a kill tore: dropped too.
        keep = [line for line in lines if line.endswith("\n") and _step(line) <= frames]
        if len(keep) < len(lines):
            dropped += len(lines) - len(keep)
            atomic_write(csv, lambda fh, keep=keep: fh.write("".join(keep).encode()))
    return dropped


def _step(line: str) -> float:
    try:
        return float(line.split(",", 1)[0])
    except ValueError:
        return -1.0  # a header or a torn line: kept, it is not a later step
