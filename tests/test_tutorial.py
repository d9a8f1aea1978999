"""docs/tutorial.md runs: every ``python`` and ``bash`` block, in order, in an empty folder.

The blocks use only what ships with the package (``builtin:`` maps), never the
repository's files or ``../shared``, so they work from a plain install.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.integration

PAGE = Path(__file__).resolve().parents[1] / "docs" / "tutorial.md"


def blocks() -> list[tuple[str, str]]:
    """``(language, code)`` of each fenced ``python`` or ``bash`` block, in page order."""
    found = re.findall(r"```(python|bash)\n(.*?)```", PAGE.read_text(), re.S)
    return [(lang, code) for lang, code in found]


def test_the_tutorial_needs_nothing_but_the_package() -> None:
    code = "\n".join(code for _, code in blocks())
    assert len(blocks()) >= 6
    assert "../shared" not in code
    assert "builtin:" in code


def test_every_block_runs_in_order(tmp_path: Path) -> None:
    env = {**os.environ, "PATH": f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}"}
    outputs = []
    for lang, code in blocks():
        command = [sys.executable, "-c", code] if lang == "python" else ["bash", "-ec", code]
        proc = subprocess.run(
            command, cwd=tmp_path, env=env, capture_output=True, text=True, timeout=600
        )
        assert proc.returncode == 0, f"{lang} block failed:\n{code}\n{proc.stderr[-3000:]}"
        outputs.append(proc.stdout)
    assert "random policy: TTD" in outputs[0]
    assert (tmp_path / "runs" / "usc" / "checkpoints" / "best.pt").is_file()
    assert "| usc/best |" in outputs[2]
    assert "| usc/best+search |" in outputs[2]
    assert "usc/best" in outputs[3]  # the CSV's policies, read by pandas
    assert "best rule here:" in outputs[4]
    assert (tmp_path / "runs" / "usc" / "view.html").stat().st_size > 10_000
