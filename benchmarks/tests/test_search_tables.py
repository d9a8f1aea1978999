"""The search tables: their rows are fixed settings, and the rendering pairs per seed."""

from __future__ import annotations

import numpy as np
import pytest

from benchmarks.generalist import HOLDOUT_ROW, unseen_settings
from benchmarks.scripts import search_tables

pytestmark = pytest.mark.unit


def test_every_row_builds_a_setting() -> None:
    sizes = {part: len(rows()) for part, rows in search_tables.PARTS.items()}
    assert sizes == {"table1": 24, "table2": 4, "default": 1, "holdout": 13, "unseen": 2}
    # The generalist's unseen settings are each in the hold-out grid or the unseen part.
    grid, extra = search_tables.holdout(), search_tables.unseen()
    assert set(extra) == {
        "selection setting: layout A, M=200, paper (trained on)",
        "LoRR warehouse_large, M=10000",
    }
    for key, (scenario, _) in unseen_settings().items():
        row = HOLDOUT_ROW.get(key, key)
        assert (grid.get(row) or extra[row]).spec() == scenario.spec(), key
    for rows in search_tables.PARTS.values():
        for scenario in rows().values():
            scenario.spec()  # every option is valid (files are read when built)


def _row(best: str, offsets: dict[str, float]) -> dict:
    rng = np.random.default_rng(0)
    base = 1000 + 50 * rng.random(20)
    ttd = {name: list(base * (1 + off)) for name, off in offsets.items()}
    ms = dict.fromkeys(offsets, 1.0)
    return {"best_rule": {"name": best}, "ttd": ttd, "ms_per_decision": ms}


def test_render_compares_with_each_rows_best_rule() -> None:
    """A search 2% below (better than) the best rule is significantly ahead; the network
    1% above it is behind; the share is (mpdm - x) / (mpdm - hindsight)."""
    rows = {
        "paper|x": _row(
            "lookahead",
            {"mpdm": 0.10, "lookahead": 0.0, "hindsight": -0.10, "network": 0.01, "search": -0.02},
        ),
    }
    text = search_tables.render("table1", rows)
    assert "| paper, x | lookahead | -1.0% [-1.0, -1.0] | **+2.0% [+2.0, +2.0]** |" in text
    assert "significantly ahead on 1, behind on 0" in text
    assert "significantly ahead on 0, behind on 1" in text
    assert "| 45% / 60% |" in text
