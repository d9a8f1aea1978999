"""A non-editable install (a wheel, as ``pip install .`` makes) carries its configs."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.system

ROOT = Path(__file__).resolve().parents[1]

RUN_EVAL = """
import sys
import rtaw_marl, rtaw_marl.cli.eval as cli
print(rtaw_marl.__file__)
sys.argv = ["rtaw-eval", "scenario=poc", "policy=[mpdm,rbts]", "seeds=[0]", "progress=false"]
cli.main()
"""


@pytest.mark.slow
def test_installed_wheel_runs_rtaw_eval_from_another_directory(tmp_path: Path) -> None:
    site = tmp_path / "site"
    subprocess.run(
        [sys.executable, "-m", "pip", "install", "--quiet", "--no-deps",
         "--no-build-isolation", "--target", str(site), str(ROOT)],
        check=True, capture_output=True, text=True, timeout=600,
    )  # fmt: skip
    assert (site / "rtaw_marl" / "conf" / "eval.yaml").is_file()
    assert (site / "rtaw_marl" / "conf" / "layout" / "A.yaml").is_file()
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    proc = subprocess.run(
        [sys.executable, "-c", RUN_EVAL], cwd=elsewhere, capture_output=True, text=True,
        env={**os.environ, "PYTHONPATH": str(site)}, timeout=300,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    # The installed copy ran, not the source tree.
    assert proc.stdout.splitlines()[0].startswith(str(site))
    assert "22.74" in proc.stdout
    assert "18.46" in proc.stdout
    assert list(elsewhere.glob("outputs/eval/*/*/results.json"))
