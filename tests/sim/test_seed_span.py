"""Seeds written in a line of text: runs of three or more joined."""

from __future__ import annotations

import pytest

from rtaw_marl.sim.inputs import seed_span

pytestmark = pytest.mark.unit


@pytest.mark.parametrize(
    ("seeds", "text"),
    [
        (range(20), "0-19"),
        ([7], "7"),
        ([3, 5, 8], "3, 5, 8"),
        ([1000, 1001], "1000, 1001"),
        ([20, 21, 22, 0, 1, 2, 9], "0-2, 9, 20-22"),
    ],
)
def test_seed_span(seeds: list[int], text: str) -> None:
    assert seed_span(seeds) == text
