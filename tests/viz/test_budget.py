"""The viewer's up-front estimate: measured constants, a refusal of what cannot fit,
nothing said or refused for a small page."""

from __future__ import annotations

import pytest

import rtaw_marl.viz.budget as budget
from rtaw_marl.errors import ConfigError
from rtaw_marl.viz.budget import available_memory, check_cost, play_cost, saved_cost

pytestmark = pytest.mark.unit

#: LoRR's warehouse_large, where the constants were measured: 500 x 140 cells.
WAREHOUSE_LARGE = 70_000


def test_the_estimate_meets_the_documented_run() -> None:
    """docs/performance.md: 10,000 robots, 5,000 timesteps, MPDM + PIBT peaked 8.3 GB;
    MPDM and batch side by side 9.1 GB."""
    one = play_cost(10_000, 5_000, 1, WAREHOUSE_LARGE)
    two = play_cost(10_000, 5_000, 2, WAREHOUSE_LARGE)
    assert 8.3e9 * 0.9 < one.nbytes < 8.3e9 * 1.1
    assert 9.1e9 * 0.9 < two.nbytes < 9.1e9 * 1.1
    assert 100 < one.seconds < 200  # 130 s quiet, 272 s loaded


def test_thirty_thousand_robots_and_two_policies_do_not_fit_24_gb() -> None:
    """The tester's run: more than a 24 GB machine has available (about 22 GB)."""
    cost = play_cost(30_000, 5_000, 2, WAREHOUSE_LARGE)
    assert cost.nbytes > 22e9
    assert cost.size() == "30,000 robots x 5,000 timesteps x 2 episodes"


def test_a_run_that_cannot_fit_is_refused_naming_what_to_lower(monkeypatch) -> None:
    monkeypatch.setattr(budget, "available_memory", lambda: 22 * 10**9)
    notes: list[str] = []
    cost = play_cost(30_000, 5_000, 2, WAREHOUSE_LARGE)
    with pytest.raises(ConfigError) as info:
        check_cost(cost, "lower sim.horizon (now 5000)", notes.append)
    text = str(info.value)
    assert text.startswith("30,000 robots x 5,000 timesteps x 2 episodes needs about 2")
    assert text.endswith(
        "more than the 22.0 GB available on this machine; lower sim.horizon (now 5000)"
    )
    assert notes == []


def test_a_small_run_is_neither_refused_nor_announced(monkeypatch) -> None:
    """10 robots, 200 timesteps on a small map: megabytes, even on a 1 GB machine."""
    monkeypatch.setattr(budget, "available_memory", lambda: 10**9)
    notes: list[str] = []
    cost = play_cost(10, 200, 2, 1_500)
    assert cost.nbytes < 100 * 2**20
    check_cost(cost, "lower sim.horizon", notes.append)
    assert notes == []


def test_a_big_run_is_announced(monkeypatch) -> None:
    monkeypatch.setattr(budget, "available_memory", lambda: 64 * 10**9)
    notes: list[str] = []
    check_cost(play_cost(10_000, 5_000, 1, WAREHOUSE_LARGE), "x", notes.append)
    (line,) = notes
    assert line.startswith("estimate: 10,000 robots x 5,000 timesteps: about 8.")
    assert "GB of memory (64.0 GB available) and about 3 min" in line


def test_a_saved_episode_costs_less_than_a_played_one() -> None:
    played = play_cost(5_000, 2_000, 1, WAREHOUSE_LARGE)
    saved = saved_cost(5_000, 2_000, 1)
    assert 0 < saved.nbytes < played.nbytes
    assert 0 < saved.seconds < played.seconds


def test_available_memory_is_read() -> None:
    available = available_memory()
    assert available is None or available > 0
