"""Load a script of ``experiments/`` as a module, for the tests of those scripts.

The scripts are not a package: they import each other by name (``import paper_tables``),
so their folder goes on ``sys.path`` once, as when they run from the command line.
"""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path
from types import ModuleType

EXPERIMENTS = Path(__file__).resolve().parents[1] / "experiments"


def load_experiment(name: str, register: bool = False) -> ModuleType:
    """A fresh module of ``experiments/<name>.py``; ``register`` also puts it in
    ``sys.modules`` under ``name`` unless one is there (dataclasses look it up)."""
    if str(EXPERIMENTS) not in sys.path:
        sys.path.insert(0, str(EXPERIMENTS))
    spec = importlib.util.spec_from_file_location(name, EXPERIMENTS / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    if register:
        sys.modules.setdefault(name, module)
    spec.loader.exec_module(module)
    return module
