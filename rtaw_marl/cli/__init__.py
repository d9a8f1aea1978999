"""Command-line entry points: thin Hydra mains over typed configs (:mod:`rtaw_marl.config`).

The console scripts point at the wrappers here, not at the Hydra mains: ``pip install
rtaw_marl`` installs the env alone, and a command whose extra is missing prints one
``error: ...`` line and exits with status 2 instead of a traceback. This module imports
only the standard library and two tables that import nothing more: the commands'
(:mod:`rtaw_marl.utils.commands`: :data:`NEEDS`, ``SUMMARIES``) and the extras'
(:mod:`rtaw_marl.errors`: :data:`EXTRAS`, whose messages the Python API's
:class:`~rtaw_marl.errors.MissingExtraError` shares).

What each command needs:

* ``rtaw-eval`` and ``rtaw-render``: the ``cli`` extra (Hydra, tqdm, matplotlib); the
  trained policies (``policy=pretrained``, ``policy=checkpoint``) also need the ``train`` extra.
* ``rtaw-results``: the ``cli`` extra (matplotlib, PyYAML through omegaconf).
* ``rtaw-train`` and ``rtaw-zoo``: the ``train`` extra (the ``cli`` extra
  plus torch, tensordict, torchrl).
* ``rtaw-export``: the ``train`` extra; ``output=*.onnx`` also the ``export`` extra (onnx,
  onnxscript, onnxruntime; checked by :mod:`rtaw_marl.policies.export`).
"""

from __future__ import annotations

import importlib
import importlib.util
import sys

from rtaw_marl.errors import EXTRAS, extra_message
from rtaw_marl.utils.commands import NEEDS

__all__ = [
    "EXTRAS",
    "NEEDS",
    "eval_main",
    "export_main",
    "lorr_main",
    "render_main",
    "results_main",
    "train_main",
    "view_main",
    "zoo_main",
]


def _fail(tool: str, extra: str, missing: str, what: str = "") -> None:
    print(f"error: {extra_message(tool + what, extra, missing)}", file=sys.stderr)
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


def zoo_main() -> None:
    """``rtaw-zoo`` (:mod:`rtaw_marl.cli.zoo`)."""
    _run("zoo")


def export_main() -> None:
    """``rtaw-export`` (:mod:`rtaw_marl.cli.export`)."""
    _run("export")


def lorr_main() -> None:
    """``rtaw-lorr`` (:mod:`rtaw_marl.cli.lorr`)."""
    _run("lorr")
