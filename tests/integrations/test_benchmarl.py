"""The BenchMARL task, tested in a process of its own (cases: ``benchmarl_cases.py``).

Importing benchmarl stores its schemas in Hydra's ConfigStore; Hydra's joblib launcher
pickles that store into its worker processes, which then import benchmarl without the
torchrl 0.14 alias that ``rtaw_marl.integrations.benchmarl`` installs, and fail. So no
test process but this one's child ever imports benchmarl.
"""

from __future__ import annotations

import importlib.util
import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.integration

# find_spec, not importorskip: importorskip would import benchmarl here.
if importlib.util.find_spec("benchmarl") is None:
    pytest.skip("benchmarl is not installed", allow_module_level=True)

CASES = Path(__file__).with_name("benchmarl_cases.py")


def test_benchmarl_task_in_its_own_process(tmp_path: Path) -> None:
    proc = subprocess.run(
        [sys.executable, "-m", "pytest", str(CASES), "-q", "-p", "no:cacheprovider",
         "--basetemp", str(tmp_path / "base")],
        capture_output=True, text=True, timeout=900, cwd=Path(__file__).parents[2],
    )  # fmt: skip
    assert proc.returncode == 0, proc.stdout[-4000:] + proc.stderr[-2000:]
    assert " passed" in proc.stdout
