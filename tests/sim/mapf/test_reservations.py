"""The reservation table: intervals, holds, safe intervals and releases."""

from __future__ import annotations

import pytest

from rtaw_marl.sim.mapf.reservations import INF, ReservationTable

pytestmark = pytest.mark.unit


def test_reservation_table_intervals_holds_and_release() -> None:
    """Runs become intervals, the last cell is held forever, release_from cuts at t."""
    table = ReservationTable(2)
    table.reserve(0, 2, [10, 10, 11, 12])  # 10 during [2, 3], 11 at 4, 12 from 5 on
    assert table.occupant(10, 1) == -1
    assert table.occupant(10, 3) == 0
    assert table.occupant(12, 10**9) == 0
    assert table.holder(12) == 0
    assert table.holder(10) == -1
    assert table.safe_intervals(10) == [(0, 1), (4, INF)]
    assert table.safe_intervals(12) == [(0, 4)]
    table.release_from(0, 4)
    assert table.occupant(11, 4) == -1
    assert table.safe_intervals(12) == [(0, INF)]
    assert table.safe_intervals(10) == [(0, 1), (4, INF)]
    table.reserve(0, 4, [10, 20])  # waiting on in cell 10 merges into its interval
    assert table.safe_intervals(10) == [(0, 1), (5, INF)]
    assert table.holder(20) == 0


def test_parked_lists_cells_held_since_a_time() -> None:
    """parked(t): cells held forever by robots standing there since t or earlier."""
    table = ReservationTable(2)
    table.reserve(0, 0, [1, 2])  # holds 2 from t = 1
    table.reserve(1, 0, [7, 7, 7, 8])  # holds 8 from t = 3
    assert sorted(table.parked(1)) == [2]
    assert sorted(table.parked(3)) == [2, 8]
    assert table.occupant(7, 2) == 1
    assert table.occupant(7, 3) == -1
