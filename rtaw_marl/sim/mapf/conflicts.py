"""Independent validation of an executed multi-robot :class:`Schedule`.

This module deliberately shares no code with the path planners: it re-derives every
rule from the raw positions so that a planner bug cannot hide itself. Time is discrete
(1 s per step); cells are ``(x, y)`` with ``x`` the column and ``y`` the row of
:attr:`Layout.obstacles`. The rules are:

1. Shapes and dtypes agree: integer ``positions [T + 1, M, 2]``, ``tasks [K, 4]`` and
   integer per-task arrays of length ``K``.
2. Every robot is, at every time, inside the grid and on a free cell.
3. Every move from ``t`` to ``t + 1`` is a wait or one 4-connected step.
4. No vertex conflict: two robots never share a cell at the same time.
5. No edge conflict: two robots never swap cells between ``t`` and ``t + 1``.
   Following a robot into the cell it has just left is allowed.
6. Each task ``k`` is served by a valid robot ``r``, with ``0 <= arrival <= assigned <=
   pickup <= delivered <= T``, and ``r`` is at the origin at the pickup time and at
   the destination at the delivery time.
7. A robot serves one task at a time: in order of assignment, each of its tasks is
   assigned no earlier than the delivery of its previous task.
8. Optionally, exactly ``expected_tasks`` tasks were served.
9. With headings (LoRR's action model): each is 0-3 (east, south, west, north); a robot
   that moves moves the way it faces and keeps its heading, and one that stays turns a
   quarter at most.

All checks are vectorised over the whole ``[T + 1, M]`` array, so a schedule of
thousands of steps and a hundred robots is validated in milliseconds.
"""

from __future__ import annotations

import numpy as np

from rtaw_marl.errors import ScheduleError
from rtaw_marl.sim.layout import Layout
from rtaw_marl.sim.mapf.schedule import Schedule

__all__ = ["check_schedule", "find_violations"]

_TASK_FIELDS = ("task_robot", "task_arrival", "task_assigned", "task_pickup", "task_delivered")


class _Report:
    """Formats at most ``limit`` messages while counting every violation."""

    def __init__(self, limit: int) -> None:
        self.limit = max(int(limit), 0)
        self.messages: list[str] = []
        self.total = 0

    def add(self, template: str, columns: tuple[np.ndarray, ...]) -> None:
        """Record one violation per row of ``columns`` (each ``[N]`` or ``[N, k]``).

        Args:
            template: ``str.format`` template taking the values of one row in order.
            columns: Integer arrays of ``N`` rows, stacked side by side.
        """
        rows = np.column_stack(columns).astype(np.int64, copy=False)
        room = max(self.limit - len(self.messages), 0)
        self.messages.extend(template.format(*row) for row in rows[:room].tolist())
        self.total += len(rows)

    def note(self, message: str) -> None:
        """Record a single violation."""
        if len(self.messages) < self.limit:
            self.messages.append(message)
        self.total += 1


def _check_shapes(schedule: Schedule) -> str | None:
    """Rule 1: the first shape or dtype problem, or ``None``."""
    pos = np.asarray(schedule.positions)
    if pos.ndim != 3 or pos.shape[0] < 1 or pos.shape[2] != 2:
        return f"positions must be [T+1, M, 2], got shape {pos.shape}"
    if not np.issubdtype(pos.dtype, np.integer):
        return f"positions must be integer, got dtype {pos.dtype}"
    tasks = np.asarray(schedule.tasks)
    if tasks.ndim != 2 or tasks.shape[1] != 4 or not np.issubdtype(tasks.dtype, np.integer):
        return f"tasks must be integer [K, 4], got {tasks.dtype} {tasks.shape}"
    for name in _TASK_FIELDS:
        arr = np.asarray(getattr(schedule, name))
        if arr.shape != (len(tasks),) or not np.issubdtype(arr.dtype, np.integer):
            return f"{name} must be integer [{len(tasks)}], got {arr.dtype} {arr.shape}"
    return None


def _check_motion(layout: Layout, pos: np.ndarray, report: _Report) -> None:
    """Rules 2-5 on ``pos`` ``int64 [T + 1, M, 2]`` with ``M >= 1``."""
    xs, ys = pos[..., 0], pos[..., 1]
    inside = (xs >= 0) & (xs < layout.width) & (ys >= 0) & (ys < layout.height)
    t, m = np.nonzero(~inside)
    size = f"{layout.width}x{layout.height}"
    report.add(
        f"out of grid at t={{}}: robot {{}} at (x={{}}, y={{}}) outside the {size} grid",
        (t, m, pos[t, m]),
    )
    blocked = np.zeros_like(inside)
    blocked[inside] = layout.obstacles[ys[inside], xs[inside]]
    t, m = np.nonzero(blocked)
    report.add("obstacle at t={}: robot {} on blocked cell (x={}, y={})", (t, m, pos[t, m]))

    t, m = np.nonzero(np.abs(np.diff(pos, axis=0)).sum(axis=-1) > 1)
    report.add(
        "illegal move from t={} to t={}: robot {} jumps (x={}, y={}) -> (x={}, y={})",
        (t, t + 1, m, pos[t, m], pos[t + 1, m]),
    )

    # Cell codes over the bounding box of all positions (robust to out-of-grid values).
    x0, y0 = min(int(xs.min()), 0), min(int(ys.min()), 0)
    codes = (ys - y0) * (max(int(xs.max()) + 1, layout.width) - x0) + (xs - x0)

    # Vertex conflicts: equal neighbours once every time row is sorted.
    order = np.argsort(codes, axis=1, kind="stable")
    ranked = np.take_along_axis(codes, order, axis=1)
    t, j = np.nonzero(ranked[:, 1:] == ranked[:, :-1])
    a, b = order[t, j], order[t, j + 1]
    report.add(
        "vertex conflict at t={}: robots {} and {} both at (x={}, y={})",
        (t, np.minimum(a, b), np.maximum(a, b), pos[t, a]),
    )

    # Edge conflicts: two moves along one undirected edge, at the same t, in opposite ways.
    t, m = np.nonzero(codes[:-1] != codes[1:])
    src, dst = codes[t, m], codes[t + 1, m]
    lo, hi, fwd = np.minimum(src, dst), np.maximum(src, dst), src < dst
    idx = np.lexsort((fwd, hi, lo, t))
    i, k = idx[:-1], idx[1:]
    swap = (t[i] == t[k]) & (lo[i] == lo[k]) & (hi[i] == hi[k]) & (fwd[i] != fwd[k])
    t, a, b = t[i[swap]], m[i[swap]], m[k[swap]]
    a, b = np.minimum(a, b), np.maximum(a, b)
    report.add(
        "edge conflict from t={} to t={}: robots {} and {} swap (x={}, y={}) <-> (x={}, y={})",
        (t, t + 1, a, b, pos[t, a], pos[t, b]),
    )


def _check_tasks(schedule: Schedule, pos: np.ndarray, report: _Report) -> None:
    """Rules 6-7."""
    horizon, num_robots = pos.shape[0] - 1, pos.shape[1]
    tasks = np.asarray(schedule.tasks, dtype=np.int64)
    robot, arrival, assigned, pickup, delivered = (
        np.asarray(getattr(schedule, n), dtype=np.int64) for n in _TASK_FIELDS
    )
    valid = (robot >= 0) & (robot < num_robots)
    k = np.flatnonzero(~valid)
    report.add(f"task {{}}: robot index {{}} out of range (M={num_robots})", (k, robot[k]))
    ordered = (arrival >= 0) & (arrival <= assigned) & (assigned <= pickup)
    ordered &= (pickup <= delivered) & (delivered <= horizon)
    k = np.flatnonzero(~ordered)
    report.add(
        f"task {{}}: times out of order: arrival={{}}, assigned={{}}, pickup={{}}, "
        f"delivered={{}} (need 0 <= arrival <= assigned <= pickup <= delivered <= "
        f"T={horizon})",
        (k, arrival[k], assigned[k], pickup[k], delivered[k]),
    )

    stops = (
        ("pickup", pickup, tasks[:, :2], "origin"),
        ("delivery", delivered, tasks[:, 2:], "destination"),
    )
    for event, when, target, place in stops:
        k = np.flatnonzero(valid & (when >= 0) & (when <= horizon))
        at = pos[when[k], robot[k]]
        wrong = (at != target[k]).any(axis=1)
        k, at = k[wrong], at[wrong]
        report.add(
            f"task {{}}: robot {{}} at {event} t={{}} is at (x={{}}, y={{}}), not at the "
            f"{place} (x={{}}, y={{}})",
            (k, robot[k], when[k], at, target[k]),
        )

    ids = np.flatnonzero(valid)
    # Ties in assignment time go by delivery: a task with no travel (origin, destination
    # and robot on one cell) is done at its assignment and the robot takes another.
    ids = ids[np.lexsort((delivered[ids], assigned[ids], robot[ids]))]
    prev, nxt = ids[:-1], ids[1:]
    clash = (robot[prev] == robot[nxt]) & (assigned[nxt] < delivered[prev])
    prev, nxt = prev[clash], nxt[clash]
    report.add(
        "overlapping tasks of robot {}: task {} assigned at t={} before task {} is "
        "delivered at t={}",
        (robot[nxt], nxt, assigned[nxt], prev, delivered[prev]),
    )


#: The cell change ``(dx, dy)`` of a forward move facing east, south, west, north.
_FORWARD = np.array([[1, 0], [0, 1], [-1, 0], [0, -1]], dtype=np.int64)


def _check_headings(heading: np.ndarray, pos: np.ndarray, report: _Report) -> None:
    """Rule 9 (``heading int [T + 1, M]``; ``pos`` already passed rule 3)."""
    if heading.shape != pos.shape[:2]:
        report.note(f"headings have shape {heading.shape}, positions {pos.shape[:2]}")
        return
    t, m = np.nonzero((heading < 0) | (heading > 3))
    report.add("robot {} at t={} has heading {} (not 0-3)", (m, t, heading[t, m]))
    if len(t):
        return
    step = pos[1:] - pos[:-1]  # [T, M, 2]
    moved = step.any(axis=-1)
    facing = _FORWARD[heading[:-1]]
    t, m = np.nonzero(moved & ((step != facing).any(axis=-1) | (heading[1:] != heading[:-1])))
    report.add(
        "robot {} moves from t={} to t={} by (dx={}, dy={}) facing heading {} (to {})",
        (m, t, t + 1, step[t, m], heading[t, m], heading[t + 1, m]),
    )
    turn = (heading[1:] - heading[:-1]) % 4
    t, m = np.nonzero(~moved & (turn == 2))
    report.add("robot {} turns a half turn from t={} to t={}", (m, t, t + 1))


def _collect(layout: Layout, schedule: Schedule, expected_tasks: int | None, limit: int) -> _Report:
    """Run every rule, keeping at most ``limit`` messages and the total count."""
    report = _Report(limit)
    problem = _check_shapes(schedule)
    if problem is not None:
        report.note(problem)
        return report
    pos = np.asarray(schedule.positions, dtype=np.int64)
    if pos.shape[1] > 0:
        _check_motion(layout, pos, report)
        if schedule.headings is not None and not report.total:
            _check_headings(np.asarray(schedule.headings, dtype=np.int64), pos, report)
    _check_tasks(schedule, pos, report)
    served = len(schedule.tasks)
    if expected_tasks is not None and served != expected_tasks:
        report.note(f"expected {expected_tasks} served tasks, schedule has {served}")
    return report


def find_violations(
    layout: Layout, schedule: Schedule, expected_tasks: int | None = None, limit: int = 20
) -> list[str]:
    """List the rule violations of an executed schedule.

    Args:
        layout: The grid the schedule was executed on.
        schedule: Positions of every robot over time and the life of every task.
        expected_tasks: When given, the number of tasks that must have been served.
        limit: Most messages returned.

    Returns:
        At most ``limit`` one-line messages naming the time, robots and cells, e.g.
        ``"vertex conflict at t=12: robots 3 and 7 both at (x=4, y=9)"``, grouped by
        rule and sorted by time within a rule; empty when the schedule is valid.
    """
    return _collect(layout, schedule, expected_tasks, limit).messages


def check_schedule(layout: Layout, schedule: Schedule, expected_tasks: int | None = None) -> None:
    """Validate an executed schedule.

    Args:
        layout: The grid the schedule was executed on.
        schedule: Positions of every robot over time and the life of every task.
        expected_tasks: When given, the number of tasks that must have been served.

    Raises:
        ScheduleError: The schedule breaks a rule; the message is the first violation
            and the number of others.
    """
    report = _collect(layout, schedule, expected_tasks, limit=1)
    if report.total:
        more = report.total - 1
        suffix = f" (and {more} more violation{'s' if more != 1 else ''})" if more else ""
        raise ScheduleError(f"{report.messages[0]}{suffix}")
