"""Every Python snippet of docs/integrations.md runs as written (skipped when one of the
libraries it imports is missing)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

pytestmark = pytest.mark.integration

PAGE = Path(__file__).resolve().parents[2] / "docs" / "integrations.md"
SNIPPETS = re.findall(r"```python\n(.*?)```", PAGE.read_text(), re.S)
COMMON = {"gymnasium", "numpy", "rtaw_marl"}


def imported(code: str) -> list[str]:
    """Top-level names of the modules a snippet imports, in order."""
    return re.findall(r"^(?:from|import) (\w+)", code, re.M)


def name(code: str) -> str:
    """The library a snippet is about: its first import outside the common ones."""
    return next((m for m in imported(code) if m not in COMMON), "gymnasium")


def test_the_page_has_a_snippet_per_library() -> None:
    names = {name(code) for code in SNIPPETS}
    assert names >= {"tianshou", "gymnasium", "sb3_contrib", "supersuit", "torchrl"}


@pytest.mark.filterwarnings("ignore:PettingZoo in TorchRL is tested using:UserWarning")
@pytest.mark.parametrize("code", SNIPPETS, ids=[name(code) for code in SNIPPETS])
def test_snippet_runs(code: str, capsys: pytest.CaptureFixture) -> None:
    for module in imported(code):
        pytest.importorskip(module)
    exec(compile(code, str(PAGE), "exec"), {"__name__": "snippet"})
    capsys.readouterr()
