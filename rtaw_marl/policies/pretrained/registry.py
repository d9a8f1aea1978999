"""The registry of shipped pretrained RTAW policies.

Each entry is the exact ``rtaw-train`` overrides that produced ``<name>.pt`` in this
folder (``experiments/train_pretrained.py`` reruns them). Policies trained with 10 robots
also run with 100 or 1000: the network's size does not depend on them.
"""

from __future__ import annotations

import sys
from pathlib import Path

from rtaw_marl.errors import ConfigError, unknown_name

__all__ = ["PRETRAINED", "pretrained_path", "train_command"]

_COMMON = ["algo=ppo_fast", "frames=102400", "eval.every_frames=10240", "seed=0"]

#: Defaults of the time these policies were trained that have changed since (docs/
#: training.md); ``train_command`` pins them. Retraining now gives equivalent policies,
#: not bit-identical ones: advantages are computed in one critic pass since then.
_THEN_DEFAULTS = ["collector.envs_per_worker=16", "eval.seeds=[1000,1001,1002,1003,1004]"]

#: name -> the rtaw-train overrides each checkpoint records (besides output_dir, progress).
PRETRAINED: dict[str, list[str]] = {
    "open60_direct_m10": ["layout=open", "navigator=direct", "env.num_robots=10", *_COMMON],
    **{
        f"{p}_astar_m10": [f"layout={p}", "navigator=astar", "env.num_robots=10", *_COMMON]
        for p in "ABCDE"
    },
    "open60_direct_m100": ["layout=open", "navigator=direct", "env.num_robots=100", *_COMMON],
    # Scalability (Table II): large grids with random tasks spread over the whole grid.
    "open300_direct_m100_random": [
        "layout=open", "layout.width=300", "layout.height=300", "navigator=direct",
        "tasks=random", "env.num_robots=100", *_COMMON,
    ],
    "C256_astar_m100_random": [
        "layout=C", "layout.width=256", "layout.height=256", "navigator=astar",
        "tasks=random", "env.num_robots=100", *_COMMON,
    ],
}  # fmt: skip


def train_command(name: str, run_dir: Path) -> list[str]:
    """The command that trains entry ``name`` into ``run_dir``."""
    if name not in PRETRAINED:
        raise unknown_name("pretrained policy", name, list(PRETRAINED))
    exe = str(Path(sys.executable).with_name("rtaw-train"))
    return [exe, *PRETRAINED[name], *_THEN_DEFAULTS, f"output_dir={run_dir}", "progress=false"]


def pretrained_path(name: str) -> Path:
    """The shipped checkpoint of entry ``name``.

    Raises:
        ConfigError: Unknown name (the message lists them) or the file is missing.
    """
    if name not in PRETRAINED:
        raise unknown_name("pretrained policy", name, list(PRETRAINED))
    path = Path(__file__).resolve().parent / f"{name}.pt"
    if not path.is_file():
        raise ConfigError(
            f"pretrained policy {name!r} is not shipped in this copy ({path} is missing); "
            f"train it with: python experiments/train_pretrained.py {name}"
        )
    return path
