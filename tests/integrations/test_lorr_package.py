"""LoRR in one place: every public LoRR name resolves from rtaw_marl.integrations.lorr,
and importing the package loads nothing heavy (LoRR's own process imports through it)."""

from __future__ import annotations

import importlib
import subprocess
import sys

import pytest

import rtaw_marl.integrations.lorr as lorr

pytestmark = pytest.mark.unit


@pytest.mark.parametrize("name", lorr.__all__)
def test_each_name_is_its_modules_own(name: str) -> None:
    module = importlib.import_module(lorr._NAMES[name])
    assert getattr(lorr, name) is getattr(module, name)
    assert name in getattr(module, "__all__", [name])


def test_an_unknown_name_is_an_attribute_error() -> None:
    with pytest.raises(AttributeError, match="has no attribute 'read_problme'"):
        _ = lorr.read_problme


def test_the_import_is_light() -> None:
    code = "import sys, rtaw_marl.integrations.lorr; print('numpy' in sys.modules)"
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert done.stdout.strip() == "False", done.stderr
