"""The console commands: the extra each cannot start without, and what each does.

One table for the wrappers of :mod:`rtaw_marl.cli` (they check a command's extra before
importing it) and for ``python -m rtaw_marl`` (it lists the commands). It lives in this
bottom layer, not in :mod:`rtaw_marl.cli`, because ``rtaw_marl/__main__.py`` belongs to
the package's top module, which may import only this layer. Standard library only, like
:mod:`rtaw_marl.errors` (whose extras table it uses): both answer on an install without
any extra.
"""

from __future__ import annotations

from rtaw_marl.errors import EXTRAS, extra_modules

__all__ = ["NEEDS", "SUMMARIES"]

#: Command (``rtaw-<command>``) -> (the extra to name in the error, the modules it cannot
#: start without). Every key is a console script of pyproject.toml (tests/test_package.py).
NEEDS: dict[str, tuple[str, tuple[str, ...]]] = {
    "eval": ("cli", ("hydra", "omegaconf", "tqdm")),
    "render": ("cli", ("hydra", "omegaconf", "matplotlib", "PIL")),
    "view": ("cli", ("hydra", "omegaconf", "tqdm")),
    # Combines results.json files: plain argparse, a plot, the sweep's overrides.yaml.
    "results": ("cli", ("matplotlib", "yaml")),
    "train": ("train", extra_modules("train")),
    # Retraining the shipped policies: rtaw-train's needs.
    "zoo": ("train", extra_modules("train")),
    # The lorr extra (the cli extra and pybind11) is what to install; the kit's build
    # needs pybind11 only for rtaw_marl's schedulers: checked there.
    "lorr": ("lorr", ("hydra", "omegaconf")),
    # TorchScript needs torch only; .onnx checks the export extra itself.
    "export": ("train", EXTRAS["train"]),
}

#: Command -> what it does, in one line (``python -m rtaw_marl`` lists them, in this order).
SUMMARIES: dict[str, str] = {
    "eval": "evaluate policies on seeded episodes: TTD tables with paired intervals",
    "train": "train an RTAW or RTAW+ policy with PPO (TorchRL)",
    "render": "play one episode with collision-aware execution: a GIF, or LoRR's JSON",
    "view": "one or two episodes in a self-contained interactive HTML page",
    "results": "combine a sweep's results.json files into one table and plot",
    "zoo": "retrain the shipped policies with their recipes",
    "export": "a trained policy as a checked TorchScript or ONNX (export extra) file",
    "lorr": "rtaw_marl's schedulers inside the League of Robot Runners' simulator",
}
