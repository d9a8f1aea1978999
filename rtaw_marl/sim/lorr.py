"""The League of Robot Runners' 2024 problems as a scenario source (``layout=lorr``,
``tasks=lorr``, ``scenario=lorr``), read and checked in full by one reader.

A LoRR problem is a JSON file naming, relative to itself, a MovingAI ``mapFile``, an
``agentFile`` of start cells and a ``taskFile`` of tasks, with ``teamSize`` robots and
``numTasksReveal``: at every timestep ``int(numTasksReveal x teamSize)`` tasks are
revealed and not yet finished (the start kit multiplies in single precision and
truncates), a finished task replaced by the next one of the file, which cycles
(``task_id % len(tasks)``, as the start kit's ``TaskManager``).

Here that window is the queue: ``sim.queue_len = int(numTasksReveal x M)`` with
``sim.refill=finish`` (the revealed tasks include the ``M`` in progress), in
``episode_mode=horizon`` episodes of LoRR's 5,000 timesteps by default.

Files (the start kit's ``Input_Output_Format.md``): ``.agents`` and ``.tasks`` start
with an optional ``# version ...`` line, then a count, then one line per robot (a
location) or task (comma-separated locations, visited in order). A location is
linearized, ``row x width + column``, so ``x = loc % width`` and ``y = loc // width``.

:func:`read_problem` is the one reader: ``rtaw-eval scenario=lorr``, ``rtaw-lorr`` and
the viewer take a problem only through it, so all of them accept and refuse the same
files, before any work. It refuses, with one line naming the file, the line and the
key: a problem JSON that is not an object of the five keys; a referenced file outside
the problem's folder (a symbolic link to the JSON is followed first, so every reader and
LoRR's ``lifelong`` use the same folder); a map, agent or task file that does not parse;
``teamSize`` above the agent file's count; a non-finite ``numTasksReveal`` or one that
reveals no more tasks than robots; two robots on one start cell or a start on an
obstacle; a task file with no task; and a task of other than two errands (every LoRR
2024 task is a pickup and a delivery). A task whose pickup is its delivery (LoRR's files
hold a few) is kept and takes a timestep, as in LoRR, which checks one errand per robot
and timestep.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np

from rtaw_marl.errors import ConfigError, TaskFileError
from rtaw_marl.sim.layout import Layout, load_layout
from rtaw_marl.sim.maps import resolve_path
from rtaw_marl.sim.tasks import TaskStream

__all__ = [
    "LORR_HORIZON",
    "LORR_SIM",
    "LoRRProblem",
    "LoRRTasks",
    "lorr_sim",
    "read_agents",
    "read_lorr_tasks",
    "read_problem",
    "reveal_window",
]

#: LoRR 2024's episode length (timesteps), the default horizon of ``scenario=lorr``.
LORR_HORIZON = 5000
#: An episode draws this many times the tasks its robots could finish if every task
#: were as short as the file's mean pickup-to-delivery distance (the file cycled), so
#: the stream does not run out before the horizon.
POOL_FACTOR = 2

#: The simulator keys of every LoRR scenario: fixed-horizon episodes with LoRR's window.
LORR_SIM: dict[str, object] = {
    "episode_mode": "horizon",
    "horizon": LORR_HORIZON,
    "refill": "finish",
    "reassign": True,
}

_KEYS = ("mapFile", "agentFile", "taskFile", "teamSize", "numTasksReveal")
_FILES = ("mapFile", "agentFile", "taskFile")
#: The start kit keeps counts in C++ ``int``: a window past this overflows there.
_INT_MAX = 2**31 - 1


def reveal_window(reveal: float, num_robots: int) -> int:
    """Revealed tasks with ``num_robots`` robots, as the start kit computes them:
    ``int(float(numTasksReveal) * M)``, a single-precision product truncated
    (``TaskManager::set_num_tasks_reveal``)."""
    return int(np.float32(reveal) * np.float32(num_robots))


@dataclass(frozen=True, eq=False)
class LoRRProblem:
    """A LoRR problem file, read and checked in full (:func:`read_problem`).

    Attributes:
        path: The JSON file (a symbolic link followed).
        map_path: Its map (absolute, resolved against the JSON's folder).
        agents_path: Its start cells.
        tasks_path: Its tasks.
        team_size: ``teamSize``, the robots of the problem.
        reveal: ``numTasksReveal``, revealed tasks per robot.
        grid: The map.
        agents: The agent file's start cells ``int64 [A, 2]`` ``(x, y)``, read-only.
        tasks: The task file's tasks ``int64 [T, 4]`` ``(ox, oy, dx, dy)``, read-only.
    """

    path: Path
    map_path: Path
    agents_path: Path
    tasks_path: Path
    team_size: int
    reveal: float
    grid: Layout
    agents: np.ndarray
    tasks: np.ndarray

    def layout(self) -> Layout:
        """The problem's map."""
        return self.grid

    def mean_task_length(self) -> float:
        """The mean Manhattan distance from pickup to delivery of the file's tasks (at
        least 1): a lower bound on a robot's timesteps per task."""
        lengths = np.abs(self.tasks[:, :2] - self.tasks[:, 2:]).sum(axis=1)
        return max(1.0, float(lengths.mean()))

    def window(self, num_robots: int) -> int:
        """Revealed tasks with ``num_robots`` robots (:func:`reveal_window`)."""
        return reveal_window(self.reveal, num_robots)


def read_problem(path: str | Path) -> LoRRProblem:
    """Read a LoRR 2024 problem JSON and check it in full (module docstring).

    A read is cached while the four files are unchanged (the config resolvers ask for
    one problem several times).

    Args:
        path: The JSON file, or ``builtin:NAME`` for a shipped problem
            (:mod:`rtaw_marl.sim.maps`; ``builtin:random_32_32_20_100.json``).

    Raises:
        ConfigError: ``builtin:`` names no shipped map (the message lists them).
        TaskFileError: The problem or a file it names is missing, malformed, outside the
            problem's folder or inconsistent; the message names the file and the key.
        LayoutError: The map is malformed, or a start or task cell is not free.
    """
    path = resolve_path(path)
    if not path.is_file():
        raise TaskFileError(f"LoRR problem file not found: {path}")
    path = path.resolve()
    data = _problem_json(path)
    files = {key: _referenced_file(path, data, key) for key in _FILES}
    team, reveal = data["teamSize"], data["numTasksReveal"]
    if isinstance(team, bool) or not isinstance(team, int) or team < 1:
        raise TaskFileError(f"{path}: teamSize must be a positive integer, got {team!r}")
    if isinstance(reveal, bool) or not isinstance(reveal, int | float) or not reveal > 1:
        raise TaskFileError(
            f"{path}: numTasksReveal must be a number above 1 (the revealed tasks include "
            f"those in progress), got {reveal!r}"
        )
    if not math.isfinite(reveal) or reveal * team > _INT_MAX:
        raise TaskFileError(
            f"{path}: numTasksReveal x teamSize must be a finite count of at most "
            f"{_INT_MAX} tasks, got {reveal!r} x {team}"
        )
    # The files' times and sizes are part of the key: a changed file is read again.
    stamp = tuple((p.stat().st_mtime_ns, p.stat().st_size) for p in (path, *files.values()))
    return _read_files(path, tuple(files.values()), team, float(reveal), stamp)


def _problem_json(path: Path) -> dict[str, Any]:
    """The problem's JSON object, with every key it needs."""
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise TaskFileError(f"{path}: not a LoRR problem (JSON): {exc}") from None
    except RecursionError:
        raise TaskFileError(f"{path}: not a LoRR problem (JSON nested too deeply)") from None
    if not isinstance(data, dict):
        raise TaskFileError(f"{path}: a LoRR problem is a JSON object with {', '.join(_KEYS)}")
    missing = [k for k in _KEYS if k not in data]
    if missing:
        raise TaskFileError(
            f"{path}: LoRR problem misses {missing[0]!r} (needs {', '.join(_KEYS)})"
        )
    return data


def _referenced_file(path: Path, data: dict[str, Any], key: str) -> Path:
    """The file ``data[key]`` names, which must exist under the problem's folder: a
    problem naming ``../../etc/passwd`` is refused without opening it."""
    name = data[key]
    if not isinstance(name, str) or not name:
        raise TaskFileError(f"{path}: {key} must be a file name, got {name!r}")
    target = (path.parent / name).resolve()
    if not target.is_relative_to(path.parent):
        raise TaskFileError(
            f"{path}: {key} {name!r} lies outside the problem's folder {path.parent} "
            "(a problem names its files under its own folder)"
        )
    if not target.is_file():
        raise TaskFileError(f"{path}: {key} {name!r} not found (looked for {target})")
    return target


@lru_cache(maxsize=8)
def _read_files(
    path: Path, files: tuple[Path, Path, Path], team: int, reveal: float, stamp: tuple
) -> LoRRProblem:
    """Read the map, agents and tasks (``files``, in :data:`_FILES` order) and check them
    against each other; ``stamp`` (the files' times and sizes) only keys the cache."""
    del stamp
    map_file, agent_file, task_file = files
    grid = load_layout(map_file)
    agents = read_agents(agent_file, grid)
    if team > len(agents):
        raise TaskFileError(
            f"{path}: teamSize {team} is more than the {len(agents)} start cells of "
            f"agentFile {agent_file.name}"
        )
    _check_distinct_starts(agents[:team], agent_file, grid.width)
    window = reveal_window(reveal, team)
    if window <= team:
        raise TaskFileError(
            f"{path}: numTasksReveal {reveal!r} reveals {window} tasks to {team} robots "
            f"(the start kit's int(numTasksReveal x teamSize)); this simulator needs at "
            f"least one more task than robots: numTasksReveal >= {(team + 1) / team:.6g}"
        )
    tasks = read_lorr_tasks(task_file, grid)
    for array in (agents, tasks):
        array.setflags(write=False)  # shared by every reader of the cache
    return LoRRProblem(path, map_file, agent_file, task_file, team, reveal, grid, agents, tasks)


def _check_distinct_starts(starts: np.ndarray, path: Path, width: int) -> None:
    """Two robots never start on one cell (LoRR's simulator would run them as one)."""
    cells = starts[:, 1] * width + starts[:, 0]
    _, first, counts = np.unique(cells, return_index=True, return_counts=True)
    if (counts > 1).any():
        cell = int(cells[first[counts > 1][0]])
        robots = np.flatnonzero(cells == cell)[:2].tolist()
        raise TaskFileError(
            f"{path}: robots {robots[0]} and {robots[1]} start on the same location {cell} "
            f"(x={cell % width}, y={cell // width})"
        )


def _numbered_lines(path: Path, what: str) -> tuple[int, list[tuple[int, str]]]:
    """The count line's value and the lines after it (with line numbers)."""
    try:
        lines = path.read_text(encoding="utf-8").splitlines()
    except UnicodeDecodeError:
        raise TaskFileError(f"{path}: not a UTF-8 text file (a LoRR {what} file)") from None
    body = [(i + 1, line.strip()) for i, line in enumerate(lines) if line.strip()]
    if body and body[0][1].startswith("#"):
        body = body[1:]  # "# version for LoRR 2024"
    if not body or not body[0][1].isdigit():
        got = body[0][1][:40] if body else "nothing"
        raise TaskFileError(f"{path}: a LoRR {what} file starts with its count, got {got!r}")
    count, rest = int(body[0][1]), body[1:]
    if len(rest) != count:
        raise TaskFileError(f"{path}: header says {count} {what}s, found {len(rest)}")
    return count, rest


def _locations(text: str, where: str, cells: int) -> list[int]:
    try:
        locs = [int(v) for v in text.split(",")]
    except ValueError:
        raise TaskFileError(
            f"{where}: expected comma-separated locations, got {text[:40]!r}"
        ) from None
    bad = [v for v in locs if not 0 <= v < cells]
    if bad:
        raise TaskFileError(f"{where}: location {bad[0]} is outside the {cells}-cell map")
    return locs


def _xy(locs: np.ndarray, width: int) -> np.ndarray:
    return np.stack([locs % width, locs // width], axis=-1).astype(np.int64)


def read_agents(path: str | Path, layout: Layout) -> np.ndarray:
    """Start cells ``int64 [M, 2]`` ``(x, y)`` of a LoRR ``.agents`` file on ``layout``."""
    path = Path(path)
    cells = layout.width * layout.height
    _, rest = _numbered_lines(path, "agent")
    locs = [_locations(text, f"{path}:{n}", cells) for n, text in rest]
    if any(len(loc) != 1 for loc in locs):
        n = next(n for (n, _), loc in zip(rest, locs, strict=True) if len(loc) != 1)
        raise TaskFileError(f"{path}:{n}: an agent line holds one location")
    starts = _xy(np.array([loc[0] for loc in locs], dtype=np.int64), layout.width)
    layout.check_cells(starts, f"{path}: start of robot")
    return starts


def read_lorr_tasks(path: str | Path, layout: Layout) -> np.ndarray:
    """Tasks ``int64 [T, 4]`` ``(ox, oy, dx, dy)`` of a LoRR ``.tasks`` file on ``layout``.

    Raises:
        TaskFileError: No task, a task of other than two errands or a location off the
            map (the line is named).
        LayoutError: An errand on an obstacle.
    """
    path = Path(path)
    cells = layout.width * layout.height
    count, rest = _numbered_lines(path, "task")
    if count == 0:
        raise TaskFileError(f"{path}: holds no task (a LoRR task file needs at least one)")
    rows = []
    for n, text in rest:
        locs = _locations(text, f"{path}:{n}", cells)
        if len(locs) != 2:
            raise TaskFileError(
                f"{path}:{n}: a task has {len(locs)} errands; only pickup-then-delivery "
                "tasks (2 errands, every LoRR 2024 task) are supported"
            )
        rows.append(locs)
    linear = np.asarray(rows, dtype=np.int64)
    tasks = _xy(linear, layout.width).reshape(-1, 4)
    layout.check_cells(tasks[:, :2], f"{path}: pickup of task")
    layout.check_cells(tasks[:, 2:], f"{path}: delivery of task")
    return tasks


class LoRRTasks(TaskStream):
    """A LoRR problem's tasks in file order, cycled, and its agents' start cells.

    Args:
        problem: The problem.
        starts: ``"file"`` (the first ``M`` of its agent file) or ``"random"`` (distinct
            random free cells per episode seed, for more robots than the file holds).
    """

    def __init__(self, problem: LoRRProblem, starts: str = "file") -> None:
        if starts not in ("file", "random"):
            raise ConfigError(f"tasks.starts must be one of file, random, got {starts!r}")
        self.problem = problem
        self.starts_from = starts
        self._layout = problem.layout()
        self.tasks = problem.tasks
        self.agents = problem.agents

    def _check_layout(self, layout: Layout) -> None:
        if layout.obstacles.shape != self._layout.obstacles.shape or not np.array_equal(
            layout.obstacles, self._layout.obstacles
        ):
            raise ConfigError(
                f"tasks=lorr: the layout is not the problem's map {self.problem.map_path.name} "
                "(use layout=lorr, or scenario=lorr)"
            )

    def generate(self, rng: np.random.Generator, layout: Layout, count: int) -> np.ndarray:
        self._check_layout(layout)
        return np.resize(self.tasks, (count, 4))

    def starts(self, rng: np.random.Generator, layout: Layout, count: int) -> np.ndarray | None:
        if self.starts_from == "random":
            return None
        if count > len(self.agents):
            raise ConfigError(
                f"{self.problem.agents_path.name} holds {len(self.agents)} start cells, "
                f"sim.num_robots={count}; use tasks.starts=random for more robots"
            )
        return self.agents[:count].copy()


def lorr_sim(
    problem: LoRRProblem, num_robots: int | None = None, horizon: int = LORR_HORIZON
) -> dict[str, object]:
    """The simulator keys of a LoRR problem: its robots, reveal window, a task pool that
    outlasts the horizon, and LoRR's 5,000-timestep horizon (``num_robots`` overrides
    ``teamSize``)."""
    m = problem.team_size if num_robots is None else int(num_robots)
    if m < 1 or int(horizon) < 1:
        key, value = ("sim.num_robots", m) if m < 1 else ("sim.horizon", horizon)
        raise ConfigError(f"{key} must be >= 1, got {value}")
    per_robot = math.ceil(POOL_FACTOR * int(horizon) / problem.mean_task_length())
    return {
        "num_robots": m,
        "queue_len": problem.window(m),
        "num_tasks": m * per_robot + problem.window(m),
        **LORR_SIM,
        "horizon": int(horizon),
    }
