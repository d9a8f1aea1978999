"""A training run on disk: its checkpoints, and resuming it without losing or repeating
anything.

``last.pt`` is written after every evaluation (and on Ctrl-C), ``best.pt`` when the
evaluation is the best yet, ``best.pt`` first: a kill between the two writes leaves a
``last.pt`` that never claims a best its folder lacks. Both writes are atomic
(:func:`~rtaw_marl.models.checkpoint.save_checkpoint`).

Resuming refuses what would silently mix two runs: a checkpoint of another model or
scenario (unless ``resume_new_scenario=true``), or a ``frames`` budget it has already
spent; and a payload that is incomplete or ill-typed (:func:`check_training_payload`),
before any work. It removes the temporary files of a write that a kill interrupted, and
cuts the CSV logs back to the checkpoint, so the rows a killed run wrote after its last
checkpoint are not followed by the same steps again.

A kill during the ``last.pt`` write that follows a new ``best.pt`` leaves ``last.pt``
one evaluation behind its sibling ``best.pt``: resuming from that ``last.pt`` resumes
from the newer ``best.pt`` instead (one line says so), so no evaluation is repeated. The
bar a new ``best.pt`` must beat is the TTD recorded in the ``best.pt`` on disk.
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from rtaw_marl.errors import ConfigError, missing_extra

# Without the training extra: one error that names it (errors.missing_extra), no traceback
# of a bare ModuleNotFoundError.
try:
    import torch
except ModuleNotFoundError as exc:
    raise missing_extra(exc, __name__, "train") from None

from rtaw_marl.models.checkpoint import Actor, Critic, load_checkpoint, plain_model, save_checkpoint
from rtaw_marl.training.config import TrainConfig, upgrade_config
from rtaw_marl.utils.atomic import atomic_write
from rtaw_marl.utils.plain import as_plain

__all__ = [
    "Checkpoints",
    "Progress",
    "check_training_payload",
    "clean_interrupted_writes",
    "resume",
    "score",
    "top_name",
    "trim_csv_logs",
]

#: The config groups that define what a run is evaluated on.
SCENARIO_KEYS = ("sim", "layout", "navigator", "tasks")


@dataclass
class Progress:
    """Where a run stands (restored on resume)."""

    frames: int = 0
    iteration: int = 0
    #: The best evaluation's selection score so far (lower is better: its mean TTD, or
    #: minus its mean tasks finished with ``selection.metric=tasks_finished``).
    best_score: float = float("inf")


def score(row: dict[str, float]) -> float:
    """An evaluation row's selection score (rows stored before ``score``: their TTD)."""
    return float(row.get("score", row["ttd"]))


class Checkpoints:
    """``best.pt`` when an evaluation is strictly better than the best so far (a tie
    keeps the earlier one), then ``last.pt``.

    Args:
        cfg: The run's config (stored in every checkpoint).
        folder: ``<run_dir>/checkpoints``.
        nets: The actor and critic networks.
        optim: Their optimizer.
        progress: The run's progress (frames, iteration, best selection score).
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
        # Strictly better only: a tie or a worse row never replaces the best on disk.
        better = score(row) < self.progress.best_score
        if better:
            self.progress.best_score = score(row)
        payload = self._payload(row, history)
        if better:
            save_checkpoint(self.best, payload)
        save_checkpoint(self.last, payload)
        if self.cfg.selection.keep > 1:
            self._keep_top(payload, history)

    def _keep_top(self, payload: dict[str, Any], history: list[dict[str, float]]) -> None:
        """``top/<frames>.pt`` for the ``selection.keep`` best evaluations of ``history`` (ties:
        the earlier), weights only; a file that drops out of them is removed. Decided
        from the history alone, so a resumed run keeps the same files."""
        top = sorted(history, key=lambda r: (score(r), r["frames"]))[: self.cfg.selection.keep]
        kept = {top_name(int(r["frames"])) for r in top}
        folder = self.last.parent / "top"
        name = top_name(self.progress.frames)
        if name in kept:
            folder.mkdir(exist_ok=True)
            save_checkpoint(folder / name, {k: v for k, v in payload.items() if k != "optimizer"})
        for old in folder.glob("*.pt") if folder.is_dir() else ():
            if old.name not in kept:
                old.unlink()

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
            "best_ttd": progress.best_score,  # the selection score (stored name kept)
            "eval": row,  # the evaluation's own row (its TTDs), not the selection config
            "history": list(history),
        }


def top_name(frames: int) -> str:
    """The file name of the kept checkpoint at ``frames`` (``selection.keep``)."""
    return f"{frames:012d}.pt"


def resume(
    cfg: TrainConfig,
    nets: tuple[Actor, Critic],
    optim: torch.optim.Optimizer,
    run_dir: Path,
) -> tuple[Progress, list[dict[str, float]]]:
    """Load ``cfg.resume`` (or its newer sibling ``best.pt``) into the networks and
    optimizer; returns the progress and the evaluation history to continue from.

    Raises:
        ConfigError: The checkpoint is damaged or incomplete, of another model, of
            another scenario (without ``resume_new_scenario``), holds no optimizer state
            (a shipped policy), already holds ``frames`` frames, or leaves a budget that
            is not a whole number of batches.
    """
    path, ckpt = _newest(Path(cfg.resume))
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
    check_training_payload(ckpt, path)
    frames, batch = ckpt["frames"], cfg.algo.frames_per_batch
    if cfg.frames <= frames:
        raise ConfigError(
            f"resume: the checkpoint has already trained {frames} frames; "
            f"frames={cfg.frames} must be larger to train on"
        )
    if (cfg.frames - frames) % batch:
        low = frames + (cfg.frames - frames) // batch * batch
        nearest = f"{low} or {low + batch}" if low > frames else f"{low + batch}"
        raise ConfigError(
            f"resume: frames={cfg.frames} leaves {cfg.frames - frames} frames after the "
            f"checkpoint's {frames}, not a whole number of batches of "
            f"algo.frames_per_batch={batch}: use frames={nearest}"
        )
    changes = scenario_changes(ckpt.get("config", {}), as_plain(cfg))
    if changes and not cfg.resume_new_scenario:
        raise ConfigError(
            f"resume: {path} was trained on another scenario ({'; '.join(changes[:3])}); "
            "its best TTD does not compare. Pass resume_new_scenario=true to continue "
            "training it here with a fresh best"
        )
    try:
        for net, name in zip(nets, ("actor", "critic"), strict=True):
            net.load_state_dict(ckpt["model"][name])
        optim.load_state_dict(ckpt["optimizer"])
    except (RuntimeError, ValueError, KeyError, TypeError) as exc:
        reason = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise ConfigError(f"resume: {path} does not fit this run's networks: {reason}") from None
    progress = Progress(frames, ckpt["iteration"], float(ckpt["best_ttd"]))
    history = list(ckpt.get("history", []))
    if changes:
        progress.best_score, history = float("inf"), []
    else:
        progress.best_score = _best_on_disk(path, run_dir)
    torch.manual_seed(cfg.seed + progress.iteration)
    return progress, history


def _newest(path: Path) -> tuple[Path, dict[str, Any]]:
    """``path`` and its checkpoint, or its sibling ``best.pt`` when that holds more frames.

    ``best.pt`` is written before ``last.pt`` with the same payload, so a ``best.pt``
    ahead of ``last.pt`` means the kill came during the ``last.pt`` write: resuming from
    ``best.pt`` continues exactly where the run was, and no evaluation is repeated.
    """
    ckpt = load_checkpoint(path)
    sibling = path.parent / "best.pt"
    if path.name != "last.pt" or not sibling.is_file():
        return path, ckpt
    best = load_checkpoint(sibling)
    frames, best_frames = ckpt.get("frames"), best.get("frames")
    if _count(frames) and _count(best_frames) and best_frames > frames:
        print(
            f"resume: {sibling} ({best_frames} frames) is newer than {path} ({frames} "
            "frames, its write was interrupted): resuming from it",
            file=sys.stderr,
        )
        return sibling, best
    return path, ckpt


def _best_on_disk(source: Path, run_dir: Path) -> float:
    """The score a new ``best.pt`` must beat: that of the run folder's ``best.pt`` (brought
    from ``source``'s folder when resuming into a new one), or infinity without one."""
    best = run_dir / "checkpoints" / "best.pt"
    sibling = source.parent / "best.pt"
    if not best.exists() and sibling.is_file():
        # Resumed into a new folder: bring the best along, or best.pt would be missing
        # until a later evaluation beats it.
        atomic_write(best, lambda fh: fh.write(sibling.read_bytes()))
    if not best.exists():
        return float("inf")
    ckpt = load_checkpoint(best)
    row = ckpt.get("eval", {})
    value = row.get("score", row.get("ttd", ckpt.get("best_ttd")))
    if not _number(value):
        raise ConfigError(f"resume: {best} records no evaluation score to compare with")
    return float(value)


def _count(value: object) -> bool:
    return isinstance(value, int) and not isinstance(value, bool) and value >= 0


def _number(value: object) -> bool:
    ok = isinstance(value, (int, float)) and not isinstance(value, bool)
    return ok and not math.isnan(value)


def check_training_payload(ckpt: dict[str, Any], path: Path) -> None:
    """Refuse a checkpoint whose training state cannot be resumed from, before any work.

    ``history`` may be missing (runs saved before it was stored); when present it must
    be a list of evaluation rows, each with integer ``frames``.

    Raises:
        ConfigError: The first missing or ill-typed field, named.
    """
    for key in ("frames", "iteration"):
        if not _count(ckpt.get(key)):
            raise ConfigError(
                f"checkpoint {path}: {key} must be an integer >= 0, got {ckpt.get(key)!r}"
            )
    if not _number(ckpt.get("best_ttd")):
        raise ConfigError(
            f"checkpoint {path}: best_ttd must be a number, got {ckpt.get('best_ttd')!r}"
        )
    history = ckpt.get("history", [])
    if not isinstance(history, list) or not all(isinstance(row, dict) for row in history):
        raise ConfigError(f"checkpoint {path}: history must be a list of evaluation rows")
    if not all(_count(row.get("frames")) for row in history):
        raise ConfigError(f"checkpoint {path}: a history row has no integer frames")
    if not isinstance(ckpt.get("eval", {}), dict):
        raise ConfigError(
            f"checkpoint {path}: eval must be a dict, got {type(ckpt['eval']).__name__}"
        )
    optimizer = ckpt.get("optimizer")
    if not isinstance(optimizer, dict) or not {"state", "param_groups"} <= set(optimizer):
        raise ConfigError(
            f"checkpoint {path}: its optimizer state lacks state or param_groups, so it "
            "cannot be resumed (it can still be evaluated)"
        )


def scenario_changes(old: dict[str, Any], new: dict[str, Any]) -> list[str]:
    """``["sim.num_robots: 10 -> 100", ...]``: where two runs' scenarios differ (the
    groups of :data:`SCENARIO_KEYS` and the selection seeds). Either config may be a
    stored one under old names (``eval`` and ``env`` sections:
    :func:`~rtaw_marl.training.config.upgrade_config`)."""
    old, new = upgrade_config(old), upgrade_config(new)
    changes = []
    for group in SCENARIO_KEYS:
        a, b = old.get(group, {}), new.get(group, {})
        for key in sorted(set(a) | set(b)):
            if a.get(key) != b.get(key):
                changes.append(f"{group}.{key}: {a.get(key)!r} -> {b.get(key)!r}")
    a, b = old.get("selection", {}).get("seeds"), new.get("selection", {}).get("seeds")
    if a != b:
        changes.append(f"selection.seeds: {a} -> {b}")
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
