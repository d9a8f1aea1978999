"""The League of Robot Runners' 2024 problems as a scenario source (``layout=lorr``,
``tasks=lorr``, ``scenario=lorr``).

A LoRR problem is a JSON file naming, relative to itself, a MovingAI ``mapFile``, an
``agentFile`` of start cells and a ``taskFile`` of tasks, with ``teamSize`` robots and
``numTasksReveal``: at every timestep ``ceil(numTasksReveal x teamSize)`` tasks are
revealed and not yet finished, a finished task replaced by the next one of the file,
which cycles (``task_id % len(tasks)``, as the start kit's ``TaskManager``).

Here that window is the queue: ``env.queue_len = ceil(numTasksReveal x M)`` with
``env.refill=finish`` (the revealed tasks include the ``M`` in progress), in
``episode_mode=horizon`` episodes of LoRR's 5,000 timesteps by default.

Files (the start kit's ``Input_Output_Format.md``): ``.agents`` and ``.tasks`` start
with an optional ``# version ...`` line, then a count, then one line per robot (a
location) or task (comma-separated locations, visited in order). A location is
linearized, ``row x width + column``, so ``x = loc % width`` and ``y = loc // width``.
Every LoRR 2024 task has two errands (pickup, delivery); a task with another number is
refused, since a task here is one pickup and one delivery.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from rtaw_marl.errors import ConfigError, TaskFileError
from rtaw_marl.sim.layout import Layout, load_layout
from rtaw_marl.sim.maps import resolve_path
from rtaw_marl.sim.tasks import TaskStream

__all__ = [
    "LORR_ENV",
    "LORR_HORIZON",
    "LoRRProblem",
    "LoRRTasks",
    "lorr_env",
    "read_agents",
    "read_lorr_tasks",
    "read_problem",
]

#: LoRR 2024's episode length (timesteps), the default horizon of ``scenario=lorr``.
LORR_HORIZON = 5000
#: An episode draws this many times the tasks its robots could finish if every task
#: were as short as the file's mean pickup-to-delivery distance (the file cycled), so
#: the stream does not run out before the horizon.
POOL_FACTOR = 2

#: The simulator keys of every LoRR scenario: fixed-horizon episodes with LoRR's window.
LORR_ENV: dict[str, object] = {
    "episode_mode": "horizon",
    "horizon": LORR_HORIZON,
    "refill": "finish",
}

_KEYS = ("mapFile", "agentFile", "taskFile", "teamSize", "numTasksReveal")


@dataclass(frozen=True)
class LoRRProblem:
    """A LoRR problem file, read.

    Attributes:
        path: The JSON file.
        map_path: Its map (absolute, resolved against the JSON's folder).
        agents_path: Its start cells.
        tasks_path: Its tasks.
        team_size: ``teamSize``, the robots of the problem.
        reveal: ``numTasksReveal``, revealed tasks per robot.
    """

    path: Path
    map_path: Path
    agents_path: Path
    tasks_path: Path
    team_size: int
    reveal: float

    def layout(self) -> Layout:
        """The problem's map."""
        return load_layout(self.map_path)

    def mean_task_length(self) -> float:
        """The mean Manhattan distance from pickup to delivery of the file's tasks (at
        least 1): a lower bound on a robot's timesteps per task."""
        tasks = read_lorr_tasks(self.tasks_path, self.layout())
        return max(1.0, float(np.abs(tasks[:, :2] - tasks[:, 2:]).sum(axis=1).mean()))

    def window(self, num_robots: int) -> int:
        """Revealed tasks with ``num_robots`` robots: ``ceil(reveal x M)``."""
        return math.ceil(self.reveal * num_robots - 1e-9)


def read_problem(path: str | Path) -> LoRRProblem:
    """Read a LoRR 2024 problem JSON (its map, agent and task files must exist).

    Args:
        path: The JSON file, or ``builtin:NAME`` for a shipped problem
            (:mod:`rtaw_marl.sim.maps`; ``builtin:random_32_32_20_100.json``).

    Raises:
        ConfigError: ``builtin:`` names no shipped map (the message lists them).
        TaskFileError: The file is missing, not JSON, misses a key, or names a file that
            does not exist; the message names the file and the key.
    """
    path = resolve_path(path)
    if not path.is_file():
        raise TaskFileError(f"LoRR problem file not found: {path}")
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise TaskFileError(f"{path}: not a LoRR problem (JSON): {exc}") from None
    if not isinstance(data, dict):
        raise TaskFileError(f"{path}: a LoRR problem is a JSON object with {', '.join(_KEYS)}")
    missing = [k for k in _KEYS if k not in data]
    if missing:
        raise TaskFileError(
            f"{path}: LoRR problem misses {missing[0]!r} (needs {', '.join(_KEYS)})"
        )
    files = {}
    for key in ("mapFile", "agentFile", "taskFile"):
        target = path.parent / str(data[key])
        if not target.is_file():
            raise TaskFileError(f"{path}: {key} {data[key]!r} not found (looked for {target})")
        files[key] = target.resolve()
    team, reveal = data["teamSize"], data["numTasksReveal"]
    if isinstance(team, bool) or not isinstance(team, int) or team < 1:
        raise TaskFileError(f"{path}: teamSize must be a positive integer, got {team!r}")
    if isinstance(reveal, bool) or not isinstance(reveal, int | float) or not reveal > 1:
        raise TaskFileError(
            f"{path}: numTasksReveal must be a number above 1 (the revealed tasks include "
            f"those in progress), got {reveal!r}"
        )
    return LoRRProblem(
        path, files["mapFile"], files["agentFile"], files["taskFile"], team, float(reveal)
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
    """Tasks ``int64 [T, 4]`` ``(ox, oy, dx, dy)`` of a LoRR ``.tasks`` file on ``layout``."""
    path = Path(path)
    cells = layout.width * layout.height
    _, rest = _numbered_lines(path, "task")
    rows = []
    for n, text in rest:
        locs = _locations(text, f"{path}:{n}", cells)
        if len(locs) != 2:
            raise TaskFileError(
                f"{path}:{n}: a task has {len(locs)} errands; only pickup-then-delivery "
                "tasks (2 errands, every LoRR 2024 task) are supported"
            )
        rows.append(locs)
    xy = _xy(np.asarray(rows, dtype=np.int64), layout.width)
    tasks = xy.reshape(-1, 4)
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
        self.tasks = read_lorr_tasks(problem.tasks_path, self._layout)
        self.agents = read_agents(problem.agents_path, self._layout)

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
                f"env.num_robots={count}; use tasks.starts=random for more robots"
            )
        return self.agents[:count].copy()


def lorr_env(
    problem: LoRRProblem, num_robots: int | None = None, horizon: int = LORR_HORIZON
) -> dict[str, object]:
    """The simulator keys of a LoRR problem: its robots, reveal window, a task pool that
    outlasts the horizon, and LoRR's 5,000-timestep horizon (``num_robots`` overrides
    ``teamSize``)."""
    m = problem.team_size if num_robots is None else int(num_robots)
    per_robot = math.ceil(POOL_FACTOR * int(horizon) / problem.mean_task_length())
    return {
        "num_robots": m,
        "queue_len": problem.window(m),
        "num_tasks": m * per_robot + problem.window(m),
        **LORR_ENV,
        "horizon": int(horizon),
    }
