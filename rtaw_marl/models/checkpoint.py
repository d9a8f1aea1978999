"""Self-describing checkpoints, written atomically.

A checkpoint is a ``torch.save`` dict:

``format``        ``"rtaw_marl.checkpoint/1"``
``features``      the observation layout its model reads (columns per observation key)
``model``         ``{"actor": state_dict, "critic": state_dict}`` and ``model_config``
``optimizer``     the optimizer state
``config``        the resolved training config
``versions``      library versions (python, torch, torchrl, tensordict, numpy, rtaw_marl)
``frames``        frames collected so far; ``iteration``: updates done
``eval``          the latest evaluation figures; ``history``: every evaluation so far
``command``       the command line
``selection``     a shipped policy's second selection stage, when it had one (its pick,
                  settings, seeds and each candidate's gain)

It is written to a temporary file in the same folder, fsynced and renamed over the
target, so a kill at any moment leaves the previous or the new checkpoint, both loadable.

Checkpoints are shared between people, so they are read with ``weights_only=True``:
tensors, numbers, strings and containers only, never a pickled callable. A crafted file
is refused before any of its code can run.

Before torch reads a file, :func:`check_archive` makes sure it is one: a regular file
(a folder, FIFO, dangling symlink or symlink loop is said as such), not empty, and an
intact zip archive whose CRCs hold, so that flipped bytes inside a stored tensor are
found rather than evaluated as weights. After it, every weight (actor, critic and
optimizer state) must be finite (:func:`check_finite`).
"""

from __future__ import annotations

import dataclasses
import errno
import pickle
import platform
import re
import stat
import sys
import zipfile
from collections.abc import Iterator, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from rtaw_marl.errors import ConfigError, missing_extra

# Without the training extra: one error that names it (errors.missing_extra), no traceback
# of a bare ModuleNotFoundError.
try:
    import tensordict
    import torch
    import torchrl
    from torch.torch_version import TorchVersion
except ModuleNotFoundError as exc:
    raise missing_extra(exc, __name__, "train") from None

import rtaw_marl
from rtaw_marl.decision.features import (
    NUM_RIVALS,
    RELATION_FEATURES,
    RIVAL_FEATURES,
    ROBOT_FEATURES,
    TASK_FEATURES,
)
from rtaw_marl.models.config import MODELS, ModelConfig, RTAWConfig, RTAWPlusConfig
from rtaw_marl.models.rtaw import RTAWActor, RTAWCritic
from rtaw_marl.models.rtaw_plus import RTAWPlusActor, RTAWPlusCritic
from rtaw_marl.utils.atomic import atomic_write

__all__ = [
    "FORMAT",
    "build_networks",
    "check_archive",
    "check_finite",
    "library_versions",
    "load_checkpoint",
    "load_networks",
    "model_features",
    "plain_model",
    "save_checkpoint",
]

FORMAT = "rtaw_marl.checkpoint/1"
#: The observation columns each model reads; checked when a checkpoint is loaded.
FEATURES = {
    "rtaw": {"robots": list(ROBOT_FEATURES), "tasks": list(TASK_FEATURES)},
    "rtaw_plus": {
        "relations": list(RELATION_FEATURES),
        "rivals": [*RIVAL_FEATURES, f"top_{NUM_RIVALS}"],
        "robots": list(ROBOT_FEATURES),
    },
}

Actor = RTAWActor | RTAWPlusActor
Critic = RTAWCritic | RTAWPlusCritic


def library_versions() -> dict[str, str]:
    """Versions of the libraries a checkpoint depends on."""
    return {
        "python": platform.python_version(),
        # str(): torch's version is a str subclass that a weights-only load refuses.
        "torch": str(torch.__version__),
        "torchrl": torchrl.__version__,
        "tensordict": tensordict.__version__,
        "numpy": np.__version__,
        "rtaw_marl": rtaw_marl.__version__,
    }


def save_checkpoint(path: str | Path, payload: dict[str, Any]) -> Path:
    """Atomically write ``payload`` (plus format, features and versions) to ``path``;
    ``payload["model_config"]`` names the model (:func:`plain_model`)."""
    full = {
        "format": FORMAT,
        "features": model_features(payload["model_config"]),
        "versions": library_versions(),
        "command": sys.argv,
        **payload,
    }
    return atomic_write(path, lambda fh: torch.save(full, fh))


def load_checkpoint(path: str | Path) -> dict[str, Any]:
    """Load and validate a checkpoint, without running any code stored in it.

    Raises:
        ConfigError: The file is missing, not a regular file, empty, not an intact zip
            archive (:func:`check_archive`), holds
            anything but plain data, is not an rtaw_marl checkpoint, holds a non-finite
            weight, or was trained on a different observation layout than this version
            produces.
    """
    path = Path(path)
    check_archive(path)
    try:
        # Checkpoints written before 0.3 stored torch's version object; it is a plain
        # str subclass, so allowing it lets no code run.
        with torch.serialization.safe_globals([TorchVersion]):
            ckpt = torch.load(path, map_location="cpu", weights_only=True)
    except pickle.UnpicklingError as exc:
        found = re.search(r"GLOBAL ([\w.]+)", str(exc))
        if found is None:
            raise ConfigError(f"cannot read checkpoint {path}: {_first_line(exc)}") from exc
        raise ConfigError(
            f"refusing checkpoint {path}: it holds more than plain data (it would call "
            f"{found.group(1)} when loaded)"
        ) from exc
    except Exception as exc:  # torch raises many types for a corrupt file
        raise ConfigError(f"cannot read checkpoint {path}: {_first_line(exc)}") from exc
    if not isinstance(ckpt, dict) or ckpt.get("format") != FORMAT:
        raise ConfigError(f"{path} is not an rtaw_marl checkpoint (expected format {FORMAT})")
    for key in ("model_config", "model"):
        if not isinstance(ckpt.get(key), dict):
            raise ConfigError(f"checkpoint {path} has no {key!r} dict")
    expected = model_features(ckpt["model_config"])
    if ckpt.get("features") != expected:
        raise ConfigError(
            f"checkpoint {path} was trained on observation features {ckpt.get('features')}, "
            f"this version produces {expected}"
        )
    check_finite(ckpt, path)
    return ckpt


def check_archive(path: Path) -> None:
    """Refuse a path that is not a readable, intact ``torch.save`` zip archive.

    Raises:
        ConfigError: One line naming ``path`` and what it is instead.
    """
    try:
        info = path.stat()
    except FileNotFoundError:
        if path.is_symlink():
            raise ConfigError(
                f"checkpoint {path} is a dangling symlink (its target is missing)"
            ) from None
        raise ConfigError(f"checkpoint not found: {path}") from None
    except OSError as exc:
        if exc.errno == errno.ELOOP:
            raise ConfigError(f"checkpoint {path} is a symlink loop") from None
        raise ConfigError(f"cannot read checkpoint {path}: {exc.strerror or exc}") from None
    if not stat.S_ISREG(info.st_mode):
        raise ConfigError(f"checkpoint {path} is {_file_kind(info.st_mode)}, not a file")
    if info.st_size == 0:
        raise ConfigError(f"checkpoint {path} is empty (0 bytes)")
    try:
        with open(path, "rb") as fh:
            head = fh.read(1)
        is_zip = zipfile.is_zipfile(path)
        if is_zip:
            with zipfile.ZipFile(path) as archive:
                names, bad = archive.namelist(), archive.testzip()
    except (zipfile.BadZipFile, EOFError, ValueError) as exc:
        raise ConfigError(f"checkpoint {path} is a damaged zip archive: {exc}") from None
    except OSError as exc:
        raise ConfigError(f"cannot read checkpoint {path}: {exc.strerror or exc}") from None
    if not is_zip:
        raise ConfigError(_not_zip(path, head))
    if bad is not None:
        raise ConfigError(f"checkpoint {path} is damaged: {bad} fails its CRC check")
    if not any(name.endswith("/data.pkl") for name in names):
        raise ConfigError(f"checkpoint {path} is a zip archive but not a torch checkpoint")


def _not_zip(path: Path, head: bytes) -> str:
    # 0x80 opens every pickle of protocol 2 and later: torch's legacy format or pickle.dump.
    if head == b"\x80":
        return (
            f"checkpoint {path} is a raw pickle (or torch's legacy non-zip format), which "
            "is never loaded as it could run code: only torch.save's zip archives are read"
        )
    return f"checkpoint {path} is not a torch checkpoint (not a zip archive)"


def _file_kind(mode: int) -> str:
    if stat.S_ISDIR(mode):
        return "a folder"
    if stat.S_ISFIFO(mode):
        return "a FIFO"
    if stat.S_ISSOCK(mode):
        return "a socket"
    return "a device"


def _tensors(tree: Any, prefix: str) -> Iterator[tuple[str, torch.Tensor]]:
    if isinstance(tree, torch.Tensor):
        yield prefix, tree
    elif isinstance(tree, Mapping):
        for key, value in tree.items():
            yield from _tensors(value, f"{prefix}.{key}")
    elif isinstance(tree, (list, tuple)):
        for i, value in enumerate(tree):
            yield from _tensors(value, f"{prefix}.{i}")


def check_finite(ckpt: Mapping[str, Any], path: str | Path) -> None:
    """Refuse a checkpoint with a NaN or infinite weight or optimizer moment (a policy
    with one acts as an all-zero actor, or fails mid-run).

    Raises:
        ConfigError: Naming the first non-finite tensor, e.g. ``model.actor.head.weight``.
    """
    for root in ("model", "optimizer"):
        for name, tensor in _tensors(ckpt.get(root), root):
            if tensor.is_floating_point() and not bool(torch.isfinite(tensor).all()):
                bad = int((~torch.isfinite(tensor)).sum())
                raise ConfigError(
                    f"checkpoint {path}: {name} holds {bad} non-finite value(s) (NaN or inf)"
                )


def load_networks(ckpt: Mapping[str, Any], path: str | Path) -> tuple[Actor, Critic]:
    """The actor and critic of a loaded checkpoint, built from its ``model_config``.

    Raises:
        ConfigError: The weights are missing or do not fit the model the checkpoint
            describes (a key missing or unexpected, a tensor of another shape).
    """
    actor, critic = build_networks(ckpt["model_config"])
    for name, net in (("actor", actor), ("critic", critic)):
        state = ckpt["model"].get(name)
        if not isinstance(state, Mapping):
            raise ConfigError(f"checkpoint {path} has no {name} weights")
        try:
            net.load_state_dict(state)
        except (RuntimeError, KeyError, TypeError) as exc:
            raise ConfigError(
                f"checkpoint {path}: the {name} weights do not fit its model_config "
                f"{dict(ckpt['model_config'])}: {_first_line(exc).strip()}"
            ) from exc
    return actor, critic


def _first_line(exc: BaseException) -> str:
    lines = [line for line in str(exc).splitlines() if line.strip()]
    return lines[1] if len(lines) > 1 and lines[0].endswith(":") else (lines or [""])[0]


def plain_model(model: ModelConfig | Mapping[str, Any]) -> dict[str, Any]:
    """A model option (or a checkpoint's ``model_config``) as a checkpoint's
    ``model_config``, every key filled in.

    ``rtaw`` configs store their sizes only (as since the first release, so that old
    checkpoints compare equal on resume); every other model stores its ``name`` too. A
    mapping gets the defaults of keys added since it was written, so a checkpoint from
    before a new model key compares equal to a config with that key's default.

    Raises:
        ConfigError: A mapping with an unknown model or key.
    """
    out = dataclasses.asdict(_typed_model(model))
    if out.get("name") == "rtaw":
        out.pop("name")
    return out


def _typed_model(model: ModelConfig | Mapping[str, Any]) -> ModelConfig:
    if isinstance(model, (RTAWConfig, RTAWPlusConfig)):
        return model
    name = model.get("name", "rtaw")
    if name not in MODELS:
        raise ConfigError(f"unknown model {name!r}; valid models: {', '.join(MODELS)}")
    cls = MODELS[name]
    allowed = [f.name for f in dataclasses.fields(cls)]
    unknown = sorted(set(model) - set(allowed))
    if unknown:
        raise ConfigError(f"unknown key model.{unknown[0]}; valid keys: {', '.join(allowed)}")
    return cls(**model)


def model_features(model: ModelConfig | Mapping[str, Any]) -> dict[str, list[str]]:
    """The observation columns the model reads (stored in and checked against checkpoints)."""
    return FEATURES[_typed_model(model).name]


def build_networks(model: ModelConfig | Mapping[str, Any]) -> tuple[Actor, Critic]:
    """Fresh actor and critic networks for a model option (or a checkpoint's
    ``model_config`` mapping; one without ``name`` is ``rtaw``).

    Raises:
        ConfigError: A key or model name is unknown (the message lists the valid ones),
            or a value is invalid.
    """
    model = _typed_model(model)
    if isinstance(model, RTAWPlusConfig):
        return (
            RTAWPlusActor(model.embed_dim, model.heads),
            RTAWPlusCritic(
                model.embed_dim,
                model.heads,
                model.critic_hidden,
                model.critic_fleet,
                summary=model.fleet_summary,
            ),
        )
    robot_in, task_in = len(ROBOT_FEATURES), len(TASK_FEATURES)
    actor = RTAWActor(robot_in, task_in, model.embed_dim, model.head_dim)
    critic = RTAWCritic(robot_in, task_in, model.embed_dim, model.critic_hidden)
    return actor, critic
