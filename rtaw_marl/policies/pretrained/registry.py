"""The shipped pretrained RTAW policies: their names and checkpoint files.

Each ``<name>.pt`` in this folder is a self-describing checkpoint (its config and the
``rtaw-train`` command that trained it): ``load_policy(name)`` loads it. The names come
from the one recipe table beside them (:data:`~rtaw_marl.policies.pretrained.recipes.
RECIPES`: how each was trained), which the zoo (:mod:`rtaw_marl.training.zoo`) turns
into commands; ``rtaw-zoo NAME`` retrains one. Policies trained with 10 robots also run
with 100 or 1000: the networks' sizes do not depend on them.
"""

from __future__ import annotations

from pathlib import Path

from rtaw_marl.errors import ConfigError, unknown_name
from rtaw_marl.policies.pretrained.recipes import RECIPES

__all__ = ["PRETRAINED", "SHIPPED", "pretrained_path"]

#: This folder: the shipped checkpoints.
SHIPPED = Path(__file__).resolve().parent

#: Every shipped policy's name, in the recipe table's order: ``<scenario>`` is the
#: paper's network and ``<scenario>_plus`` RTAW+ (409,600 PPO frames); Table II's
#: 500-robot RTAW+ (``*_m500_random_plus``); Table I's at three times the budget
#: (``*_long``, ``*_long_plus``); ``generalist_plus``.
PRETRAINED: tuple[str, ...] = tuple(RECIPES)


def pretrained_path(name: str) -> Path:
    """The shipped checkpoint of policy ``name``.

    Raises:
        ConfigError: Unknown name (the message lists them) or the file is missing.
    """
    if name not in PRETRAINED:
        raise unknown_name("pretrained policy", name, list(PRETRAINED))
    path = SHIPPED / f"{name}.pt"
    if not path.is_file():
        raise ConfigError(
            f"pretrained policy {name!r} is not shipped in this copy ({path} is missing); "
            f"retrain it with: rtaw-zoo {name}"
        )
    return path
