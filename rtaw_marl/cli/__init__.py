"""Command-line entry points: thin Hydra mains over typed configs (:mod:`rtaw_marl.config`).

The console scripts point at the wrappers here, not at the Hydra mains: ``pip install
rtaw_marl`` installs the env alone, and a command whose extra is missing prints one
``error: ...`` line and exits with status 2 instead of a traceback. This module imports
only the standard library.

What each command needs:

* ``rtaw-eval`` and ``rtaw-render``: the ``cli`` extra (Hydra, tqdm, matplotlib); the
  trained policies (``policy=pretrained``, ``policy=checkpoint``) also need the ``train`` extra.
* ``rtaw-results``: the ``cli`` extra (matplotlib, PyYAML through omegaconf).
* ``rtaw-train``, ``rtaw-study`` and ``rtaw-zoo``: the ``train`` extra (the ``cli`` extra
  plus torch, tensordict, torchrl).
* ``rtaw-export``: the ``train`` extra; ``output=*.onnx`` also the ``export`` extra (onnx,
  onnxscript, onnxruntime; checked by :mod:`rtaw_marl.policies.export`).
"""

from __future__ import annotations

import importlib
import importlib.util
import sys

__all__ = [
    "EXTRAS",
    "NEEDS",
    "eval_main",
    "export_main",
    "lorr_main",
    "render_main",
    "results_main",
    "study_main",
    "train_main",
    "view_main",
    "zoo_main",
]

#: Extra -> the top-level modules it installs that the commands import.
EXTRAS: dict[str, tuple[str, ...]] = {
    "cli": ("hydra", "omegaconf", "tqdm", "matplotlib", "PIL"),
    "train": ("torch", "tensordict", "torchrl"),
}
_EXTRA_NAMES = {"cli": "command-line", "train": "training"}

#: Command -> (the extra to name in the error, the modules it cannot start without).
NEEDS: dict[str, tuple[str, tuple[str, ...]]] = {
    "eval": ("cli", ("hydra", "omegaconf", "tqdm")),
    "render": ("cli", ("hydra", "omegaconf", "matplotlib", "PIL")),
    "view": ("cli", ("hydra", "omegaconf", "tqdm")),
    # Combines results.json files: plain argparse, a plot, the sweep's overrides.yaml.
    "results": ("cli", ("matplotlib", "yaml")),
    "train": ("train", EXTRAS["cli"] + EXTRAS["train"]),
    # The paper's tables evaluate the shipped learned policies.
    "study": ("train", EXTRAS["cli"] + EXTRAS["train"]),
    # Retraining the shipped policies: rtaw-train's needs.
    "zoo": ("train", EXTRAS["cli"] + EXTRAS["train"]),
    # The kit's build needs pybind11 only for rtaw_marl's schedulers: checked there.
    "lorr": ("cli", ("hydra", "omegaconf")),
    # TorchScript needs torch only; .onnx checks the export extra itself.
    "export": ("train", EXTRAS["train"]),
}


def _fail(tool: str, extra: str, missing: str, what: str = "") -> None:
    print(
        f"error: {tool}{what} needs the {_EXTRA_NAMES[extra]} extra ({missing!r} is not "
        f"installed): pip install 'rtaw_marl[{extra}]'",
        file=sys.stderr,
    )
    sys.exit(2)


def _missing(module: str) -> bool:
    try:
        return importlib.util.find_spec(module) is None
    except (ImportError, ValueError):
        return True


def _run(command: str) -> None:
    tool = f"rtaw-{command}"
    extra, modules = NEEDS[command]
    for module in modules:
        if _missing(module):
            _fail(tool, extra, module)
    try:
        importlib.import_module(f"rtaw_marl.cli.{command}").main()
    except ModuleNotFoundError as exc:
        # A module of an extra imported only for some options (torch for policy=pretrained).
        root = (exc.name or "").partition(".")[0]
        for name, provided in EXTRAS.items():
            if root in provided:
                what = " with trained policies" if name == "train" else ""
                _fail(tool, name, root, what)
        raise


def eval_main() -> None:
    """``rtaw-eval`` (:mod:`rtaw_marl.cli.eval`)."""
    _run("eval")


def render_main() -> None:
    """``rtaw-render`` (:mod:`rtaw_marl.cli.render`)."""
    _run("render")


def results_main() -> None:
    """``rtaw-results`` (:mod:`rtaw_marl.cli.results`)."""
    _run("results")


def view_main() -> None:
    """``rtaw-view`` (:mod:`rtaw_marl.cli.view`)."""
    _run("view")


def train_main() -> None:
    """``rtaw-train`` (:mod:`rtaw_marl.cli.train`)."""
    _run("train")


def study_main() -> None:
    """``rtaw-study`` (:mod:`rtaw_marl.cli.study`)."""
    _run("study")


def zoo_main() -> None:
    """``rtaw-zoo`` (:mod:`rtaw_marl.cli.zoo`)."""
    _run("zoo")


def export_main() -> None:
    """``rtaw-export`` (:mod:`rtaw_marl.cli.export`)."""
    _run("export")


def lorr_main() -> None:
    """``rtaw-lorr`` (:mod:`rtaw_marl.cli.lorr`)."""
    _run("lorr")
