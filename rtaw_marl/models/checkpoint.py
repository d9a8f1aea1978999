"""Self-describing checkpoints, written atomically.

A checkpoint is a ``torch.save`` dict:

``format``        ``"rtaw_marl.checkpoint/1"``
``features``      the observation layout it was trained on (robot/task columns)
``model``         ``{"actor": state_dict, "critic": state_dict}`` and ``model_config``
``optimizer``     the optimizer state
``config``        the resolved training config
``versions``      library versions (python, torch, torchrl, tensordict, numpy, rtaw_marl)
``frames``        frames collected so far; ``iteration``: updates done
``eval``          the latest evaluation figures; ``history``: every evaluation so far
``command``       the command line

It is written to a temporary file in the same folder, fsynced and renamed over the
target, so a kill at any moment leaves the previous or the new checkpoint, both loadable.
"""

from __future__ import annotations

import dataclasses
import platform
import sys
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
import tensordict
import torch
import torchrl

import rtaw_marl
from rtaw_marl.envs.features import ROBOT_FEATURES, TASK_FEATURES
from rtaw_marl.errors import ConfigError
from rtaw_marl.models.config import RTAWConfig
from rtaw_marl.models.rtaw import RTAWActor, RTAWCritic
from rtaw_marl.utils.atomic import atomic_write

__all__ = [
    "FORMAT",
    "build_networks",
    "library_versions",
    "load_checkpoint",
    "save_checkpoint",
]

FORMAT = "rtaw_marl.checkpoint/1"
FEATURES = {"robots": list(ROBOT_FEATURES), "tasks": list(TASK_FEATURES)}


def library_versions() -> dict[str, str]:
    """Versions of the libraries a checkpoint depends on."""
    return {
        "python": platform.python_version(),
        "torch": torch.__version__,
        "torchrl": torchrl.__version__,
        "tensordict": tensordict.__version__,
        "numpy": np.__version__,
        "rtaw_marl": rtaw_marl.__version__,
    }


def save_checkpoint(path: str | Path, payload: dict[str, Any]) -> Path:
    """Atomically write ``payload`` (plus format, features and versions) to ``path``."""
    full = {
        "format": FORMAT,
        "features": FEATURES,
        "versions": library_versions(),
        "command": sys.argv,
        **payload,
    }
    return atomic_write(path, lambda fh: torch.save(full, fh))


def load_checkpoint(path: str | Path) -> dict[str, Any]:
    """Load and validate a checkpoint.

    Raises:
        ConfigError: The file is missing, is not an rtaw_marl checkpoint, or was trained
            on a different observation layout than this version produces.
    """
    path = Path(path)
    if not path.is_file():
        raise ConfigError(f"checkpoint not found: {path}")
    try:
        ckpt = torch.load(path, map_location="cpu", weights_only=False)
    except Exception as exc:  # torch raises many types for a corrupt file
        raise ConfigError(f"cannot read checkpoint {path}: {exc}") from exc
    if not isinstance(ckpt, dict) or ckpt.get("format") != FORMAT:
        raise ConfigError(f"{path} is not an rtaw_marl checkpoint (expected format {FORMAT})")
    if ckpt.get("features") != FEATURES:
        raise ConfigError(
            f"checkpoint {path} was trained on observation features {ckpt.get('features')}, "
            f"this version produces {FEATURES}"
        )
    return ckpt


def build_networks(model: RTAWConfig | Mapping[str, Any]) -> tuple[RTAWActor, RTAWCritic]:
    """Fresh actor and critic networks for a model option (or a checkpoint's
    ``model_config`` mapping).

    Raises:
        ConfigError: A key is unknown (the message lists the valid ones) or invalid.
    """
    if not isinstance(model, RTAWConfig):
        allowed = [f.name for f in dataclasses.fields(RTAWConfig)]
        unknown = sorted(set(model) - set(allowed))
        if unknown:
            raise ConfigError(f"unknown key model.{unknown[0]}; valid keys: {', '.join(allowed)}")
        model = RTAWConfig(**model)
    robot_in, task_in = len(ROBOT_FEATURES), len(TASK_FEATURES)
    actor = RTAWActor(robot_in, task_in, model.embed_dim, model.head_dim)
    critic = RTAWCritic(robot_in, task_in, model.embed_dim, model.critic_hidden)
    return actor, critic
