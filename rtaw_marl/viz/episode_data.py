"""An executed episode packed for the browser viewer (:mod:`rtaw_marl.viz.view`).

A 10,000-robot, 5,000-timestep episode holds 50 million robot positions; stored raw
they would not fit in a page. What the page gets instead, per episode:

* ``start``: ``int32 [M, 2]`` the robots' cells ``(x, y)`` at ``t = 0``;
* ``moves``: ``uint8 [M, T]`` the move of robot ``m`` from ``t`` to ``t + 1``, one of
  :data:`MOVES` (wait, +x, -x, +y, -y), robot by robot: a robot's consecutive moves
  repeat, so this order deflates to 2.2 bits an entry at 10,000 robots, 18% less than
  timestep by timestep. The page rebuilds positions from keyframes it computes on load;
* ``tasks``: ``int32 [K, 10]`` ``(ox, oy, dx, dy, robot, arrival, assigned, pickup,
  delivered, id)`` of every task in the schedule (and those robots still hold at the
  end, :func:`open_tasks`, with ``T + 1`` for what did not happen), in assignment order.
  ``id`` is the task's index in the episode's task stream (``Schedule.task_ids``): the
  same task has the same id in every episode of one seed, and for a LoRR problem it is
  LoRR's task id, the ids of LoRR's output format (:mod:`rtaw_marl.integrations.lorr.output`
  writes them, :mod:`rtaw_marl.viz.schedule_file` reads them). A schedule without
  stream ids numbers its tasks by assignment order;
* ``headings`` and ``turns`` when robots turn (``Schedule.headings``): ``uint8 [M]``
  each robot's heading at ``t = 0`` (0 east, 1 south, 2 west, 3 north) and ``uint8
  [M, T]`` its quarter turns from ``t`` to ``t + 1`` (0 none, 1 clockwise, 3
  counter-clockwise), robot by robot as the moves;
* ``congestion``: ``[B, H * W]`` per time bin, how many timesteps a robot with a task
  stood still on each cell (a wait: blocked by traffic, or by its own plan);
* ``delivered``: ``int32 [T + 1]`` tasks delivered at each timestep (the throughput).

Every array is deflated (zlib) and base64-encoded: :func:`pack` gives the JSON object
the page reads. Layout cells are ``0`` free, ``1`` obstacle, ``2`` pickup station,
``3`` delivery station.
"""

from __future__ import annotations

import base64
import zlib
from dataclasses import dataclass
from typing import Any

import numpy as np

from rtaw_marl.errors import ConfigError
from rtaw_marl.sim.layout import Layout
from rtaw_marl.sim.mapf.schedule import Schedule

__all__ = [
    "CONGESTION_BINS",
    "MOVES",
    "TASK_COLUMNS",
    "EpisodeArrays",
    "congestion",
    "encode",
    "episode_arrays",
    "layout_cells",
    "move_codes",
    "open_tasks",
    "pack",
    "turn_codes",
]

MOVES: tuple[tuple[int, int], ...] = ((0, 0), (1, 0), (-1, 0), (0, 1), (0, -1))
"""``(dx, dy)`` of move code ``0 .. 4``: wait, +x, -x, +y, -y."""

TASK_COLUMNS = 10
"""Columns of a task row: ``(ox, oy, dx, dy, robot, arrival, assigned, pickup, delivered,
id)``."""

CONGESTION_BINS = 100
"""Time bins of the congestion heat map (fewer when the episode is shorter)."""

# Rows of positions diffed at once: bounds the int64 temporaries at 10,000 robots.
_CHUNK = 512


@dataclass(frozen=True)
class EpisodeArrays:
    """One episode as the page's arrays (before deflating); see the module docstring."""

    start: np.ndarray
    moves: np.ndarray  # [T, M]
    tasks: np.ndarray
    congestion: np.ndarray
    bin_size: int
    delivered: np.ndarray
    headings: np.ndarray | None = None  # [M]
    turns: np.ndarray | None = None  # [T, M]


def layout_cells(layout: Layout) -> np.ndarray:
    """``uint8 [H, W]``: 0 free, 1 obstacle, 2 pickup station, 3 delivery station."""
    cells = layout.obstacles.astype(np.uint8)
    for code, mask in ((2, layout.pickup), (3, layout.delivery)):
        if mask is not None:
            cells[mask] = code
    return cells


def move_codes(positions: np.ndarray) -> np.ndarray:
    """``uint8 [T, M]`` move codes (:data:`MOVES`) of positions ``[T + 1, M, 2]``.

    Raises:
        ConfigError: A robot moves more than one cell in a timestep.
    """
    steps, robots = positions.shape[0] - 1, positions.shape[1]
    codes = np.zeros((steps, robots), dtype=np.uint8)
    for lo in range(0, steps, _CHUNK):
        hi = min(lo + _CHUNK, steps)
        d = np.diff(positions[lo : hi + 1], axis=0)
        if (np.abs(d).sum(axis=-1) > 1).any():
            t, m = np.argwhere(np.abs(d).sum(axis=-1) > 1)[0]
            raise ConfigError(f"robot {m} moves more than one cell at timestep {lo + t}")
        block = codes[lo:hi]
        for code, (dx, dy) in enumerate(MOVES[1:], start=1):
            block[(d[..., 0] == dx) & (d[..., 1] == dy)] = code
    return codes


def turn_codes(headings: np.ndarray) -> np.ndarray:
    """``uint8 [T, M]`` quarter turns (0 none, 1 clockwise, 3 counter-clockwise) of
    headings ``[T + 1, M]`` (0..3: east, south, west, north).

    Raises:
        ConfigError: A heading is not 0..3, or a robot turns half round in a timestep.
    """
    if ((headings < 0) | (headings > 3)).any():
        t, m = np.argwhere((headings < 0) | (headings > 3))[0]
        raise ConfigError(f"robot {m} has heading {headings[t, m]} at timestep {t}, not 0..3")
    steps = headings.shape[0] - 1
    codes = np.zeros((steps, headings.shape[1]), dtype=np.uint8)
    for lo in range(0, steps, _CHUNK):
        hi = min(lo + _CHUNK, steps)
        codes[lo:hi] = np.diff(headings[lo : hi + 1].astype(np.int8), axis=0) % 4
    if (codes == 2).any():
        t, m = np.argwhere(codes == 2)[0]
        raise ConfigError(f"robot {m} turns half round at timestep {t} (one quarter at most)")
    return codes


def _by_assignment(schedule: Schedule) -> np.ndarray:
    """``int32 [K, 10]`` the schedule's task rows in assignment order (ids ``-1`` when the
    schedule has no stream ids)."""
    order = np.argsort(schedule.task_assigned, kind="stable")
    ids = np.full(len(order), -1) if schedule.task_ids is None else schedule.task_ids[order]
    return np.column_stack(
        [
            schedule.tasks[order],
            schedule.task_robot[order],
            schedule.task_arrival[order],
            schedule.task_assigned[order],
            schedule.task_pickup[order],
            schedule.task_delivered[order],
            ids,
        ]
    ).astype(np.int32)


def _busy(tasks: np.ndarray, steps: int, robots: int) -> np.ndarray:
    """``bool [T, M]``: robot ``m`` holds a task at ``t`` (assigned <= t < delivered)."""
    change = np.zeros((steps + 1, robots), dtype=np.int16)
    robot = tasks[:, 4]
    np.add.at(change, (np.clip(tasks[:, 6], 0, steps), robot), 1)
    np.add.at(change, (np.clip(tasks[:, 8], 0, steps), robot), -1)
    return np.cumsum(change, axis=0, dtype=np.int16)[:steps] > 0


def congestion(
    positions: np.ndarray, moves: np.ndarray, tasks: np.ndarray, shape: tuple[int, int], bins: int
) -> tuple[np.ndarray, int]:
    """Waits per time bin and cell.

    Args:
        positions: ``[T + 1, M, 2]`` cells ``(x, y)``.
        moves: ``uint8 [T, M]`` move codes.
        tasks: ``int32 [K, 10]`` (:func:`episode_arrays`' rows).
        shape: The grid's ``(H, W)``.
        bins: Time bins ``B``.

    Returns:
        ``(counts [B, H * W], bin_size)``: timesteps in bin ``b`` (``t // bin_size == b``)
        at which a robot with a task stood still on each cell. A cell holds one robot
        at a time, so a count is at most ``bin_size``.
    """
    steps, robots = moves.shape
    bin_size = max(1, -(-steps // bins))
    height, width = shape
    cells = height * width
    busy = _busy(tasks, steps, robots)
    counts = np.zeros(bins * cells, dtype=np.int64)
    for lo in range(0, steps, _CHUNK):
        hi = min(lo + _CHUNK, steps)
        t, m = np.nonzero((moves[lo:hi] == 0) & busy[lo:hi])
        xy = positions[lo + t, m]
        index = ((lo + t) // bin_size) * cells + xy[:, 1] * width + xy[:, 0]
        counts += np.bincount(index, minlength=counts.size)
    return counts.reshape(bins, -1), bin_size


def open_tasks(
    schedule: Schedule,
    tasks: np.ndarray,
    task_robot: np.ndarray,
    task_arrival: np.ndarray,
    task_assigned: np.ndarray,
) -> np.ndarray:
    """Rows of the tasks a robot holds at the end that the schedule leaves out.

    A horizon episode's schedule (``navigator=pibt``) holds the tasks delivered by its
    last timestep only; a robot still on a task would look idle. The simulator's
    records hold every assignment: a robot with more assignments than scheduled tasks
    holds its last one. Its pickup is the first timestep from the assignment at which
    the robot stands on the origin (``T + 1`` if it never does); its delivery ``T + 1``;
    its id its index in the records (the task stream).

    Args:
        schedule: The executed episode.
        tasks: ``int [N, 4]`` every task of the episode (``WarehouseSim.tasks``).
        task_robot: ``int [N]`` the robot each task went to, ``-1`` if none.
        task_arrival: ``float [N]`` arrival times (NaN if the task never arrived).
        task_assigned: ``float [N]`` assignment times (NaN if never assigned).

    Returns:
        ``int32 [J, 10]`` rows as :func:`episode_arrays` orders them; ``J <= M``.
    """
    robots, end = schedule.num_robots, schedule.horizon + 1
    given = np.flatnonzero(task_robot >= 0)
    held = np.bincount(task_robot[given], minlength=robots)
    scheduled = np.bincount(schedule.task_robot, minlength=robots)
    # Each robot's last assignment: the end of its run once sorted by robot, then time.
    order = given[np.lexsort((task_assigned[given], task_robot[given]))]
    by_robot = task_robot[order]
    last = order[np.r_[by_robot[1:] != by_robot[:-1], True]] if len(order) else order
    k = last[(held > scheduled)[task_robot[last]]]
    robot, at = task_robot[k], task_assigned[k].astype(np.int64)
    # The first timestep from the assignment at which the robot stands on the origin.
    steps = np.arange(end)[:, None]
    there = (schedule.positions[:, robot] == tasks[None, k, :2]).all(axis=-1) & (steps >= at)
    pickup = np.where(there.any(axis=0), there.argmax(axis=0), end)
    return (
        np.column_stack([tasks[k], robot, task_arrival[k], at, pickup, np.full(len(k), end), k])
        .astype(np.int32)
        .reshape(-1, TASK_COLUMNS)
    )


def episode_arrays(
    layout: Layout,
    schedule: Schedule,
    bins: int = CONGESTION_BINS,
    unfinished: np.ndarray | None = None,
) -> EpisodeArrays:
    """The page's arrays of one executed episode on ``layout``, with the rows of
    :func:`open_tasks` (``unfinished``) among its tasks when given."""
    positions = schedule.positions
    steps = positions.shape[0] - 1
    if steps < 1:
        raise ConfigError("the schedule has no timestep to show")
    height, width = layout.obstacles.shape
    x, y = positions[..., 0], positions[..., 1]
    if ((x < 0) | (x >= width) | (y < 0) | (y >= height)).any():
        raise ConfigError(f"the schedule leaves the {width}x{height} grid of {layout.name!r}")
    moves = move_codes(positions)
    tasks = _by_assignment(schedule)
    if unfinished is not None and len(unfinished):
        tasks = np.concatenate([tasks, unfinished.astype(np.int32)])
        tasks = tasks[np.argsort(tasks[:, 6], kind="stable")]
    if schedule.task_ids is None:
        tasks[:, 9] = np.arange(len(tasks))
    headings = None if schedule.headings is None else np.asarray(schedule.headings)
    if headings is not None and headings.shape != positions.shape[:2]:
        raise ConfigError(
            f"the schedule's headings are {list(headings.shape)}, not one per robot and "
            f"timestep {list(positions.shape[:2])}"
        )
    bins = max(1, min(bins, steps))
    counts, bin_size = congestion(positions, moves, tasks, layout.obstacles.shape, bins)
    dtype = np.uint16 if bin_size <= np.iinfo(np.uint16).max else np.uint32
    done = tasks[:, 8]
    delivered = np.bincount(done[(done >= 0) & (done <= steps)], minlength=steps + 1)
    return EpisodeArrays(
        start=positions[0].astype(np.int32),
        moves=moves,
        tasks=tasks,
        congestion=counts.astype(dtype),
        bin_size=bin_size,
        delivered=delivered.astype(np.int32),
        headings=headings[0].astype(np.uint8) if headings is not None else None,
        turns=turn_codes(headings) if headings is not None else None,
    )


def encode(array: np.ndarray) -> dict[str, Any]:
    """An array as ``{"dtype", "shape", "data"}``: little-endian, deflated, base64."""
    flat = np.ascontiguousarray(array, dtype=array.dtype.newbyteorder("<"))
    data = base64.b64encode(zlib.compress(flat.tobytes(), 6)).decode("ascii")
    return {"dtype": flat.dtype.name, "shape": list(array.shape), "data": data}


def pack(arrays: EpisodeArrays, name: str, summary: dict[str, Any]) -> dict[str, Any]:
    """One episode as the page's JSON object (``summary``: shown beside its name)."""
    return {
        "name": name,
        "summary": summary,
        "robots": int(arrays.start.shape[0]),
        "steps": int(arrays.moves.shape[0]),
        "bin_size": arrays.bin_size,
        "start": encode(arrays.start),
        "moves": encode(arrays.moves.T),
        "tasks": encode(arrays.tasks),
        "congestion": encode(arrays.congestion),
        "delivered": encode(arrays.delivered),
        **(
            {"headings": encode(arrays.headings), "turns": encode(arrays.turns.T)}
            if arrays.headings is not None and arrays.turns is not None
            else {}
        ),
    }
