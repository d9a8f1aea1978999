"""A results file written before learned policies' labels were short reads under
today's label, so old and new files combine and compare by one name."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from rtaw_marl.evaluation.results_file import read_results
from rtaw_marl.policies.labels import upgrade_label

pytestmark = pytest.mark.unit


def test_an_old_label_reads_as_todays(tmp_path: Path) -> None:
    path = tmp_path / "results.json"
    path.write_text(json.dumps({
        "config": {"env": {"num_robots": 10}},
        "seeds": [0, 1],
        "policies": {"mpdm": {"ttd": [3.0, 4.0]}, "rtaw:generalist_plus@k32": {"ttd": [2.0, 3.0]}},
    }))  # fmt: skip
    results = read_results(path)
    assert list(results.policies) == ["mpdm", "generalist_plus@k32"]
    assert results.config["sim"] == {"num_robots": 10}


def test_upgrade_label_keeps_todays_labels() -> None:
    assert upgrade_label("rtaw:demo/best") == "demo/best"
    assert upgrade_label("generalist_plus") == "generalist_plus"
    assert upgrade_label("rtaw_like:x") == "rtaw_like:x"
