"""The shipped pretrained RTAW policies: their names and checkpoint files.

Each ``<name>.pt`` in this folder is a self-describing checkpoint (its config and the
``rtaw-train`` command that trained it): ``load_policy(name)`` loads it. How each was
trained lives beside training (:mod:`rtaw_marl.training.zoo`, its recipe), and ``rtaw-zoo
NAME`` retrains it. Policies trained with 10 robots also run with 100 or 1000: the
networks' sizes do not depend on them.
"""

from __future__ import annotations

from pathlib import Path

from rtaw_marl.errors import ConfigError, unknown_name

__all__ = ["PRETRAINED", "SHIPPED", "pretrained_path"]

#: This folder: the shipped checkpoints.
SHIPPED = Path(__file__).resolve().parent

_TABLE1 = [
    s for m in (10, 100) for s in (f"open60_direct_m{m}", *(f"{p}_astar_m{m}" for p in "ABCDE"))
]
_TRAINED = ["shelves_astar_m10", *_TABLE1, "open300_direct_m100_random", "C256_astar_m100_random"]

#: Every shipped policy's name: ``<scenario>`` is the paper's network and
#: ``<scenario>_plus`` RTAW+ (409,600 PPO frames); Table II's 500-robot RTAW+
#: (``*_m500_random_plus``); Table I's at three times the budget (``*_long``,
#: ``*_long_plus``).
PRETRAINED: tuple[str, ...] = (
    *_TRAINED,
    *(f"{n}_plus" for n in _TRAINED),
    "open300_direct_m500_random_plus",
    "C256_astar_m500_random_plus",
    *(f"{n}_long{plus}" for n in _TABLE1 for plus in ("", "_plus")),
    "generalist_plus",
)


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
