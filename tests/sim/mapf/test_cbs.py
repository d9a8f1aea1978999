"""Conflict-Based Search: validity, known optima, infeasibility, budgets, random grids."""

from __future__ import annotations

import heapq
import itertools
import time
from collections import deque

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rtaw_marl.errors import PlanningTimeout
from rtaw_marl.sim.layout import Layout
from rtaw_marl.sim.mapf import CBSSolution, CBSStats, Grid, Schedule, cbs_solve, check_schedule

pytestmark = pytest.mark.unit

# derandomize: the same 30 examples on every run and machine. Random exploration once
# drew a feasible 4x4 two-robot instance CBS could not solve within 10 s (28,003
# high-level nodes), which made `make test` fail by chance.
FAST = settings(max_examples=30, deadline=None, database=None, derandomize=True)
MOVES = ((0, 0), (1, 0), (-1, 0), (0, 1), (0, -1))
TASK_FIELDS = (
    "task_robot", "task_arrival", "task_assigned", "task_pickup", "task_delivered",
)  # fmt: skip


def grid(*rows: str) -> np.ndarray:
    """``bool [H, W]`` free mask from rows of ``.`` (free) and ``@`` (obstacle)."""
    return np.array([[c == "." for c in row] for row in rows])


def bfs_field(free: np.ndarray, x: int, y: int) -> np.ndarray:
    """4-connected distances ``int32 [H, W]`` to ``(x, y)`` on ``free``; ``-1`` unreachable."""
    height, width = free.shape
    dist = np.full((height, width), -1, dtype=np.int32)
    dist[y, x] = 0
    queue = deque([(x, y)])
    while queue:
        cx, cy = queue.popleft()
        for dx, dy in MOVES[1:]:
            nx, ny = cx + dx, cy + dy
            if 0 <= nx < width and 0 <= ny < height and free[ny, nx] and dist[ny, nx] < 0:
                dist[ny, nx] = dist[cy, cx] + 1
                queue.append((nx, ny))
    return dist


def solve(
    free: np.ndarray,
    starts: list[tuple[int, int]],
    goals: list[list[tuple[int, int]]],
    blocked: np.ndarray | None = None,
    budget: float = 5.0,
    max_nodes: int | None = None,
    max_expansions: int | None = None,
    stats: CBSStats | None = None,
) -> CBSSolution | None:
    """Run CBS on ``(x, y)`` lists; ``blocked`` (``bool [H, W]``) defaults to nothing.

    The solution's paths are returned as ``(x, y)`` arrays ``int64 [L + 1, 2]``.
    """
    grid = Grid(free)
    sol = cbs_solve(
        grid,
        [grid.cell(*s) for s in starts],
        [[grid.cell(*g) for g in agent_goals] for agent_goals in goals],
        time.perf_counter() + budget,
        blocked=[] if blocked is None else grid.cells(np.argwhere(blocked)[:, ::-1]).tolist(),
        max_nodes=max_nodes,
        max_expansions=max_expansions,
        stats=stats,
    )
    if sol is None:
        return None
    return CBSSolution([grid.xys(p) for p in sol.paths], sol.goal_times, sol.expanded)


def check_solution(
    free: np.ndarray,
    blocked: np.ndarray,
    starts: list[tuple[int, int]],
    goals: list[list[tuple[int, int]]],
    sol: CBSSolution,
) -> list[int]:
    """Assert that ``sol`` is a legal, conflict-free plan; return each agent's cost."""
    assert len(sol.paths) == len(sol.goal_times) == len(starts)
    costs = []
    for path, times, start, agent_goals in zip(
        sol.paths, sol.goal_times, starts, goals, strict=True
    ):
        assert path.dtype == np.int64
        assert times.dtype == np.int64
        assert path.ndim == 2
        assert path.shape[1] == 2
        assert tuple(path[0]) == start
        xs, ys = path[:, 0], path[:, 1]
        assert (free[ys, xs] & ~blocked[ys, xs]).all(), "path enters a non-traversable cell"
        assert (np.abs(np.diff(path, axis=0)).sum(axis=1) <= 1).all(), "illegal move"
        assert len(times) == len(agent_goals)
        prev = 0
        for k, goal in enumerate(agent_goals):
            on_goal = np.flatnonzero((path[prev:] == goal).all(axis=1)) + prev
            assert on_goal.size, f"goal {k} never visited in order"
            if k < len(agent_goals) - 1:  # intermediate goals: first visit in order
                assert times[k] == on_goal[0]
            assert tuple(path[times[k]]) == goal
            prev = int(times[k])
        assert times[-1] == len(path) - 1
        costs.append(len(path) - 1)
    # Conflicts, agents staying at their last cell forever (one step past the end suffices).
    horizon = max(costs) + 2
    pos = np.stack([np.concatenate([p, np.repeat(p[-1:], horizon - len(p), 0)]) for p in sol.paths])
    for i, j in itertools.combinations(range(len(starts)), 2):
        same = (pos[i] == pos[j]).all(axis=1)
        assert not same.any(), f"vertex conflict {i}-{j} at t={int(np.argmax(same))}"
        swap = (pos[i, :-1] == pos[j, 1:]).all(axis=1) & (pos[i, 1:] == pos[j, :-1]).all(axis=1)
        moved = (pos[i, :-1] != pos[i, 1:]).any(axis=1)
        assert not (swap & moved).any(), f"edge conflict {i}-{j}"
    # The package's independent conflict checker agrees (parked robots as extra robots).
    parked = np.argwhere(blocked)[:, ::-1]
    still = np.broadcast_to(parked, (horizon, len(parked), 2))
    schedule = Schedule(
        positions=np.concatenate([pos.transpose(1, 0, 2), still], axis=1).astype(np.int64),
        **{f: np.zeros(0, dtype=np.int64) for f in TASK_FIELDS},
        tasks=np.zeros((0, 4), dtype=np.int64),
    )
    check_schedule(Layout(~free), schedule)
    return costs


def joint_optimum(
    free: np.ndarray, starts: list[tuple[int, int]], goals: list[list[tuple[int, int]]]
) -> int | None:
    """Brute-force optimal sum of costs by Dijkstra over the joint state space.

    A state is, per agent, ``(cell, goals visited, finished)``. An agent standing on its
    last goal with all earlier goals visited may finish (stay there forever) at no cost;
    a joint time step costs one per unfinished agent.
    """
    height, width = free.shape

    def advance(cell: tuple[int, int], k: int, agent_goals: list[tuple[int, int]]) -> int:
        while k < len(agent_goals) - 1 and cell == agent_goals[k]:
            k += 1
        return k

    start = tuple((s, advance(s, 0, g), False) for s, g in zip(starts, goals, strict=True))
    dist = {start: 0}
    heap = [(0, start)]
    pairs = list(itertools.combinations(range(len(starts)), 2))
    while heap:
        d, state = heapq.heappop(heap)
        if d > dist[state]:
            continue
        if all(fin for _, _, fin in state):
            return d
        successors = []
        options = []
        for i, ((cell, k, fin), agent_goals) in enumerate(zip(state, goals, strict=True)):
            if fin:
                options.append([(cell, k, True)])
                continue
            if k == len(agent_goals) - 1 and cell == agent_goals[-1]:
                successors.append((d, (*state[:i], (cell, k, True), *state[i + 1 :])))
            opts = []
            for dx, dy in MOVES:
                nx, ny = cell[0] + dx, cell[1] + dy
                if 0 <= nx < width and 0 <= ny < height and free[ny, nx]:
                    opts.append(((nx, ny), advance((nx, ny), k, agent_goals), False))
            options.append(opts)
        step = d + sum(not fin for _, _, fin in state)
        for nxt in itertools.product(*options):
            if any(
                nxt[i][0] == nxt[j][0]
                or (nxt[i][0] == state[j][0] and nxt[j][0] == state[i][0] != nxt[i][0])
                for i, j in pairs
            ):
                continue
            successors.append((step, nxt))
        for cost, nxt in successors:
            if nxt not in dist or cost < dist[nxt]:
                dist[nxt] = cost
                heapq.heappush(heap, (cost, nxt))
    return None


def test_single_agent_cost_is_the_bfs_distance() -> None:
    free = grid(
        ".....@.",
        ".@@@.@.",
        ".@...@.",
        ".@.@@@.",
        ".......",
    )
    sol = solve(free, [(2, 2)], [[(6, 0)]])
    assert sol is not None
    (cost,) = check_solution(free, np.zeros_like(free), [(2, 2)], [[(6, 0)]], sol)
    assert cost == bfs_field(free, 6, 0)[2, 2] == 10
    assert sol.expanded == 1


def test_goal_at_start_is_reached_at_time_zero() -> None:
    free = grid("...")
    sol = solve(free, [(1, 0)], [[(1, 0)]])
    assert sol is not None
    assert sol.paths[0].tolist() == [[1, 0]]
    assert sol.goal_times[0].tolist() == [0]


def test_multi_goal_agent_visits_goals_in_order() -> None:
    free = grid(*["....."] * 5)
    goals = [[(0, 0), (4, 0), (0, 4), (4, 4)]]
    sol = solve(free, [(0, 0)], goals)
    assert sol is not None
    (cost,) = check_solution(free, np.zeros_like(free), [(0, 0)], goals, sol)
    assert cost == 4 + 8 + 4
    assert sol.goal_times[0].tolist() == [0, 4, 12, 16]


def test_swap_in_a_corridor_uses_the_side_pocket() -> None:
    free = grid(
        "@@.@@",
        ".....",
    )
    starts, goals = [(0, 1), (4, 1)], [[(4, 1)], [(0, 1)]]
    sol = solve(free, starts, goals)
    assert sol is not None
    costs = check_solution(free, np.zeros_like(free), starts, goals, sol)
    # One agent ducks into the pocket (3 steps), waits for the other, then comes back.
    assert sorted(costs) == [5, 6]
    assert joint_optimum(free, starts, goals) == 11


def test_swap_without_a_pocket_times_out() -> None:
    # CBS cannot prove this infeasible; it runs into its deadline instead.
    free = grid("....")
    with pytest.raises(PlanningTimeout, match="high-level nodes"):
        solve(free, [(0, 0), (3, 0)], [[(3, 0)], [(0, 0)]], budget=0.3)


def test_node_budget_gives_up_deterministically() -> None:
    """Past max_nodes the search returns None (no timeout); a solvable case within it."""
    free = grid("....")
    stats = CBSStats()
    assert solve(free, [(0, 0), (3, 0)], [[(3, 0)], [(0, 0)]], max_nodes=50, stats=stats) is None
    assert (stats.nodes, stats.exhausted) == (50, "max_nodes")
    pocket = grid("@@.@", "....")
    sol = solve(pocket, [(0, 1), (3, 1)], [[(3, 1)], [(0, 1)]], max_nodes=50, stats=stats)
    assert sol is not None
    assert sol.expanded == stats.nodes <= 50
    assert stats.exhausted is None
    # The low-level budget: each agent of this 60x60 crossing needs 118 expansions; the
    # first agent overdraws 100 and the second may not start.
    big = np.ones((60, 60), dtype=bool)
    starts, goals = [(0, 0), (59, 0)], [[(59, 59)], [(0, 59)]]
    assert solve(big, starts, goals, max_expansions=100, stats=stats) is None
    assert (stats.nodes, stats.expansions, stats.exhausted) == (0, 118, "max_expansions")
    assert solve(big, starts, goals, max_expansions=300, stats=stats) is not None
    assert stats.expansions == 2 * 118


def test_crossing_at_a_junction_makes_one_agent_wait() -> None:
    free = grid(
        "@.@",
        "...",
        "@.@",
    )
    starts, goals = [(0, 1), (1, 0)], [[(2, 1)], [(1, 2)]]
    sol = solve(free, starts, goals)
    assert sol is not None
    costs = check_solution(free, np.zeros_like(free), starts, goals, sol)
    assert sorted(costs) == [2, 3]
    assert sol.expanded >= 2


def test_final_goal_on_the_only_route_parks_after_the_other_passes() -> None:
    free = grid(
        ".....",
        "@@.@@",
        "@@.@@",
    )
    # Agent 0 could park on (2, 0) at t=1, but agent 1 passes there at t=2.
    starts, goals = [(2, 1), (0, 0)], [[(2, 0)], [(4, 0)]]
    sol = solve(free, starts, goals)
    assert sol is not None
    costs = check_solution(free, np.zeros_like(free), starts, goals, sol)
    assert costs == [3, 4]
    assert sol.goal_times[0].tolist() == [3]
    assert joint_optimum(free, starts, goals) == 7


def test_agent_parked_on_the_route_steps_aside_and_returns() -> None:
    free = grid(
        "@@.@@",
        ".....",
    )
    # Agent 1 starts on its final goal, on agent 0's only route: it must duck into the
    # pocket and come back, so its final goal is reached at t=3, not at t=0.
    starts, goals = [(0, 1), (2, 1)], [[(4, 1)], [(2, 1)]]
    sol = solve(free, starts, goals)
    assert sol is not None
    costs = check_solution(free, np.zeros_like(free), starts, goals, sol)
    assert costs == [4, 3]
    assert sol.goal_times[1].tolist() == [3]
    assert joint_optimum(free, starts, goals) == 7


@pytest.mark.parametrize(
    ("rows", "starts", "goals", "optimum"),
    [
        pytest.param(
            ("@...", "....", "...."),
            [(1, 0), (2, 0), (3, 1)],
            [[(3, 0), (0, 1)], [(2, 0)], [(1, 0)]],
            12,
            id="parked-start-on-route",
        ),
        pytest.param(
            ("@...", ".@..", "...."),
            [(1, 0), (2, 0), (0, 2)],
            [[(3, 0), (0, 1)], [(2, 2)], [(1, 0)]],
            19,
            id="three-agent-detours",
        ),
        pytest.param(
            ("...", "@.@", "..."),
            [(1, 2), (0, 2)],
            [[(0, 2)], [(1, 2)]],
            6,
            id="swap-through-own-goal",
        ),
    ],
)
def test_small_instances_match_the_joint_optimum(
    rows: tuple[str, ...],
    starts: list[tuple[int, int]],
    goals: list[list[tuple[int, int]]],
    optimum: int,
) -> None:
    free = grid(*rows)
    assert joint_optimum(free, starts, goals) == optimum
    sol = solve(free, starts, goals)
    assert sol is not None
    assert sum(check_solution(free, np.zeros_like(free), starts, goals, sol)) == optimum


def test_parked_robots_are_obstacles() -> None:
    free = grid(
        ".....",
        ".....",
    )
    blocked = np.zeros_like(free)
    blocked[1, 1:4] = True
    sol = solve(free, [(0, 1)], [[(4, 1)]], blocked=blocked)
    assert sol is not None
    (cost,) = check_solution(free, blocked, [(0, 1)], [[(4, 1)]], sol)
    assert cost == 6


@pytest.mark.parametrize(
    ("starts", "goals", "blocked_cells"),
    [
        pytest.param([(0, 0)], [[(6, 0)]], [(3, 0)], id="blocked-corridor"),
        pytest.param([(0, 0)], [[(4, 0), (6, 0)]], [(5, 0)], id="blocked-second-leg"),
        pytest.param([(0, 0), (6, 0)], [[(3, 0)], [(3, 0)]], [], id="same-final-goal"),
        pytest.param([(0, 0)], [[(3, 0)]], [(3, 0)], id="goal-on-blocked"),
        pytest.param([(0, 0)], [[(1, 1)]], [], id="goal-on-obstacle"),
        pytest.param([(0, 0)], [[(2, 2)]], [], id="goal-in-other-region"),
        pytest.param([(0, 0), (0, 0)], [[(1, 0)], [(2, 0)]], [], id="same-start"),
    ],
)
def test_infeasible_instances_return_none_quickly(
    starts: list[tuple[int, int]],
    goals: list[list[tuple[int, int]]],
    blocked_cells: list[tuple[int, int]],
) -> None:
    free = grid(
        ".......",
        "@@@@@@@",
        "@@.....",
    )
    blocked = np.zeros_like(free)
    for x, y in blocked_cells:
        blocked[y, x] = True
    stats = CBSStats()
    assert solve(free, starts, goals, blocked=blocked, stats=stats) is None
    # Found before any high-level node: by the checks up front, or by one static
    # low-level search (no constraints: states keyed without time, so each (cell, goal
    # index) is expanded at most once).
    assert (stats.nodes, stats.exhausted) == (0, None)
    assert stats.expansions <= int(free.sum()) * 3


def test_blocked_wall_on_a_large_grid_is_infeasible_quickly() -> None:
    """The wall cuts the goal off: one static low-level search proves it, no node."""
    free = np.ones((60, 60), dtype=bool)
    blocked = np.zeros_like(free)
    blocked[30, :] = True
    stats = CBSStats()
    assert (
        solve(free, [(5, 5), (50, 5)], [[(5, 50)], [(50, 10)]], blocked=blocked, stats=stats)
        is None
    )
    # At most every cell above the wall once (states without constraints are keyed
    # without time), then the search ends on its own.
    assert stats.nodes == 0
    assert stats.exhausted is None
    assert 0 < stats.expansions <= 30 * 60


def test_deadline_in_the_past_raises() -> None:
    free = Grid(grid(*["....."] * 5))
    with pytest.raises(PlanningTimeout, match="after 0 high-level nodes"):
        cbs_solve(free, [free.cell(0, 0)], [[free.cell(4, 4)]], time.perf_counter() - 1.0)


@st.composite
def instances(
    draw: st.DrawFn, max_side: int = 7, max_agents: int = 4, max_goals: int = 2
) -> tuple[np.ndarray, list[tuple[int, int]], list[list[tuple[int, int]]]]:
    """Connected grids with a few obstacles, distinct starts and distinct final goals."""
    width = draw(st.integers(max(2, max_side - 2), max_side))
    height = draw(st.integers(max(2, max_side - 2), max_side))
    free = np.ones((height, width), dtype=bool)
    cells = [(x, y) for y in range(height) for x in range(width)]
    for x, y in draw(st.lists(st.sampled_from(cells), max_size=max_side - 1)):
        if free.sum() <= 2 * max_agents:
            break
        free[y, x] = False
        first_free = next(c for c in cells if free[c[1], c[0]])
        if (bfs_field(free, *first_free) < 0).sum() > (~free).sum():
            free[y, x] = True  # keep the grid connected
    open_cells = [c for c in cells if free[c[1], c[0]]]
    agents = draw(st.integers(2, max_agents))
    starts = draw(
        st.lists(st.sampled_from(open_cells), min_size=agents, max_size=agents, unique=True)
    )
    finals = draw(
        st.lists(st.sampled_from(open_cells), min_size=agents, max_size=agents, unique=True)
    )
    goals = [
        [*draw(st.lists(st.sampled_from(open_cells), max_size=max_goals - 1)), final]
        for final in finals
    ]
    return free, starts, goals


@FAST
@given(instances())
def test_random_instances_are_conflict_free(
    instance: tuple[np.ndarray, list[tuple[int, int]], list[list[tuple[int, int]]]],
) -> None:
    free, starts, goals = instance
    try:
        sol = solve(free, starts, goals, budget=1.0)
    except PlanningTimeout:
        return  # CBS does not detect every infeasible instance
    if sol is None:
        return
    costs = check_solution(free, np.zeros_like(free), starts, goals, sol)
    for cost, start, agent_goals in zip(costs, starts, goals, strict=True):
        legs = [start, *agent_goals]
        bound = sum(int(bfs_field(free, *b)[a[1], a[0]]) for a, b in itertools.pairwise(legs))
        assert cost >= bound


@FAST
@given(instances(max_side=4, max_agents=2, max_goals=2))
def test_random_small_instances_are_optimal(
    instance: tuple[np.ndarray, list[tuple[int, int]], list[list[tuple[int, int]]]],
) -> None:
    free, starts, goals = instance
    expected = joint_optimum(free, starts, goals)
    if expected is None:
        return  # CBS cannot prove infeasibility; it would only run into its deadline
    sol = solve(free, starts, goals, budget=10.0)
    assert sol is not None
    assert sum(check_solution(free, np.zeros_like(free), starts, goals, sol)) == expected
