"""The SIPP search on hand-made corridors with known optima."""

from __future__ import annotations

import numpy as np
import pytest

from rtaw_marl.errors import PlanningTimeout
from rtaw_marl.sim.layout import Layout, open_grid
from rtaw_marl.sim.mapf import Grid, ReservationTable, Schedule, check_schedule, sipp_plan

pytestmark = pytest.mark.unit

#: A one-cell pocket above x = 3 of a 7-cell corridor (y = 1).
POCKET = Layout(np.array([[c == "@" for c in row] for row in ("@@@.@@@", ".......")]))


class Planner:
    """sipp_plan on (x, y) cells of a layout, with reservations given as (x, y) paths."""

    def __init__(self, layout: Layout, robots: int = 3) -> None:
        self.grid = Grid.from_layout(layout)
        self.table = ReservationTable(robots)

    def reserve(self, robot: int, t0: int, path: list[tuple[int, int]]) -> None:
        self.table.reserve(robot, t0, [self.grid.cell(*xy) for xy in path])

    def plan(
        self,
        start: tuple[int, int],
        goals: list[tuple[int, int]],
        t0: int = 0,
        deadline: float | None = None,
    ) -> tuple[list[tuple[int, int]], list[int]] | None:
        found = sipp_plan(
            self.grid, self.table, self.grid.cell(*start), t0,
            [self.grid.cell(*g) for g in goals],
            deadline if deadline is not None else float("inf"),
        )  # fmt: skip
        if found is None:
            return None
        cells, times = found
        return [self.grid.xy(c) for c in cells], times


def test_free_grid_path_is_the_shortest_path() -> None:
    """Without reservations the arrival time is the BFS distance, goals in order."""
    p = Planner(open_grid(6, 5))
    path, times = p.plan((0, 0), [(5, 0), (5, 4)])
    assert times == [5, 9]
    assert (path[0], path[5], path[-1]) == ((0, 0), (5, 0), (5, 4))
    assert len(path) == 10


def test_waits_in_the_pocket_for_an_oncoming_robot() -> None:
    """Robot 1 runs the corridor right to left; the planner dodges into the pocket.

    The optimum is 7 (BFS distance 5): it must be in the pocket when robot 1 passes
    x = 3 at t = 3 and can come back at t = 4.
    """
    p = Planner(POCKET)
    p.reserve(1, 0, [(x, 1) for x in range(6, -1, -1)])  # holds (0, 1) from t = 6
    path, times = p.plan((1, 1), [(6, 1)])
    assert times == [7]
    assert (3, 0) in path
    other = [(max(6 - t, 0), 1) for t in range(len(path))]
    empty = np.zeros(0, dtype=np.int64)
    schedule = Schedule(
        positions=np.array([path, other], dtype=np.int64).transpose(1, 0, 2),
        tasks=np.zeros((0, 4), dtype=np.int64), task_robot=empty, task_arrival=empty,
        task_assigned=empty, task_pickup=empty, task_delivered=empty,
    )  # fmt: skip
    check_schedule(POCKET, schedule)


def test_no_swap_in_a_corridor_without_room() -> None:
    """An oncoming robot in a one-wide corridor that ends behind the planner: no path."""
    p = Planner(open_grid(5, 1))
    p.reserve(1, 0, [(4, 0), (3, 0), (2, 0), (1, 0), (0, 0)])
    assert p.plan((1, 0), [(3, 0)]) is None


def test_follows_a_robot_that_leads_the_way() -> None:
    """Moving into the cell another robot just left is allowed: no wait needed."""
    p = Planner(open_grid(6, 1))
    p.reserve(1, 0, [(1, 0), (2, 0), (3, 0), (4, 0), (5, 0)])
    path, times = p.plan((0, 0), [(4, 0)])
    assert times == [4]
    assert path == [(0, 0), (1, 0), (2, 0), (3, 0), (4, 0)]


def test_goal_held_by_another_robot_fails_fast() -> None:
    """A final goal another robot holds forever cannot be reached."""
    p = Planner(open_grid(4, 4))
    p.reserve(1, 0, [(3, 3)])
    assert p.plan((0, 0), [(3, 3)]) is None
    # As an intermediate goal it is fine to visit before the holder arrives.
    q = Planner(open_grid(4, 4))
    q.reserve(1, 0, [(3, 0)] * 3 + [(3, 1), (3, 2), (3, 3)])  # at (3, 3) from t = 5
    path, times = q.plan((0, 3), [(3, 3), (0, 0)])
    assert times == [3, 9]
    assert path[3] == (3, 3)


def test_waits_for_a_robot_that_crosses_the_goal() -> None:
    """The final cell must be free forever: arrive after the last robot passes it."""
    p = Planner(open_grid(5, 3))
    # Robot 1 passes (2, 1) at t = 6 on its way down.
    p.reserve(1, 0, [(2, 0)] * 6 + [(2, 1), (2, 2)])
    path, times = p.plan((0, 1), [(2, 1)])
    assert times == [7]
    assert path[-1] == (2, 1)


def test_deadline_raises() -> None:
    p = Planner(open_grid(8, 8))
    with pytest.raises(PlanningTimeout, match="time limit"):
        p.plan((0, 0), [(7, 7)], deadline=0.0)
