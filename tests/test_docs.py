"""The docs stay true: the env page matches its docstring and the README example runs."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.integration

ROOT = Path(__file__).resolve().parents[1]


def test_environment_page_is_generated_from_docstring() -> None:
    """docs/environment.md is the env module docstring (regenerate with gen_env_doc.py)."""
    proc = subprocess.run(
        [sys.executable, "-m", "benchmarks.scripts.gen_env_doc", "--check"],
        capture_output=True,
        text=True,
        cwd=ROOT,
    )
    assert proc.returncode == 0, proc.stderr


def test_readme_python_example_runs() -> None:
    """The README's env example runs and prints a positive TTD."""
    readme = (ROOT / "README.md").read_text()
    code = re.search(r"```python\n(.*?)```", readme, re.S)
    assert code is not None
    proc = subprocess.run(
        [sys.executable, "-c", code.group(1)], capture_output=True, text=True, cwd=ROOT
    )
    assert proc.returncode == 0, proc.stderr
    assert float(proc.stdout.strip()) > 0


def test_readme_links_exist() -> None:
    """Every relative link of the README points at a file (anchors aside)."""
    readme = (ROOT / "README.md").read_text()
    links = re.findall(r"\]\(([^)#]+)(?:#[^)]*)?\)", readme)
    local = [link for link in links if "://" not in link]
    assert len(local) > 10
    for link in local:
        assert (ROOT / link).exists(), link


def test_configuration_page_documents_every_key() -> None:
    """docs/configuration.md's key reference is generated from the schemas, and every key
    of every option has a line in its schema's docstring (gen_config_doc.py)."""
    proc = subprocess.run(
        [sys.executable, "-m", "benchmarks.scripts.gen_config_doc", "--check"],
        capture_output=True,
        text=True,
        cwd=ROOT,
    )
    assert proc.returncode == 0, proc.stderr
