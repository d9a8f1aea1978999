"""The documentation site builds offline (`make docs`) and its API reference has content.

``mkdocs build --strict`` fails on a module of docs/api/ that mkdocstrings cannot collect,
on a warning of mkdocstrings or griffe and on a page of the nav that does not exist;
links that leave docs/ are only reported (mkdocs.yml, ``validation``). The page checks
catch the silent failure: a reference that renders no object at all.
"""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.integration

pytest.importorskip("mkdocs", reason="the docs extra: pip install -e '.[docs]'")
pytest.importorskip("mkdocstrings_handlers.python", reason="the docs extra")

ROOT = Path(__file__).resolve().parents[1]

#: Names each API page must document (site/api/<page>/index.html).
DOCUMENTED = {
    "envs": ["rtaw_marl.envs.pettingzoo", "raw_env", "WarehouseEnv", "BatchedWarehouseEnv"],
    "sim": ["rtaw_marl.sim.core", "WarehouseSim", "build_sim", "rtaw_marl.sim.distances"],
    "policies": ["load_policy", "NetworkPolicy", "MPDM", "Lookahead", "Policy"],
    "models": ["RTAWActor", "RTAWPlusActor", "rtaw_marl.models.checkpoint"],
    "training": ["rtaw_marl.training.ppo", "TrainResult", "rtaw_marl.training.config"],
    "evaluation": ["rtaw_marl.evaluation.evaluate", "rtaw_marl.evaluation.stats"],
}


@pytest.fixture(scope="module")
def site(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("site")
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "mkdocs",
            "build",
            "--strict",
            "-f",
            str(ROOT / "mkdocs.yml"),
            "--site-dir",
            str(out),
        ],
        capture_output=True,
        text=True,
        cwd=ROOT,
        timeout=600,
    )
    assert proc.returncode == 0, proc.stderr[-4000:]
    return out


@pytest.mark.parametrize("page", sorted(DOCUMENTED))
def test_api_page_documents_its_names(site: Path, page: str) -> None:
    html = (site / "api" / page / "index.html").read_text()
    # mkdocstrings gives every rendered object a `doc doc-object` block: none means the
    # directive rendered nothing.
    assert "doc-object" in html
    missing = [name for name in DOCUMENTED[page] if name not in html]
    assert not missing, missing


def test_user_pages_are_built(site: Path) -> None:
    assert (site / "index.html").is_file()
    assert (site / "environment" / "index.html").is_file()
    assert (site / "api" / "index.html").is_file()


def test_site_loads_nothing_from_the_network(site: Path) -> None:
    """No page pulls a script, a stylesheet or a font from another host (the built-in
    theme's highlight.js CDN is off): the site works offline."""
    remote = re.compile(r"<(?:script|link|img)\b[^>]*\b(?:src|href)=\"(?:https?:)?//", re.I)
    pages = [p for p in site.rglob("*.html") if remote.search(p.read_text())]
    assert not pages, [str(p.relative_to(site)) for p in pages]
