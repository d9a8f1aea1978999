"""Task streams, task CSV files and the layout/task-stream registry."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from rtaw_marl.errors import ConfigError, LayoutError, TaskFileError
from rtaw_marl.sim.layout import Layout, open_grid
from rtaw_marl.sim.options import (
    DesignatedTasksConfig,
    ShelvesLayoutConfig,
    layout_option,
    task_option,
)
from rtaw_marl.sim.tasks import (
    DEFAULT_CENTRES,
    POC_TASKS,
    TWO_TASKS,
    DesignatedTasks,
    FixedTasks,
    RandomTasks,
    TaskStream,
    load_task_csv,
)

pytestmark = pytest.mark.unit

#: Two regions: a 2-cell column on the left, a 3x3 block on the right.
TWO_REGIONS = np.array([[c == "@" for c in row] for row in ("..@...", "@.@...", "@@@...")])


def _rng(seed: int) -> np.random.Generator:
    return np.random.default_rng(seed)


def _write(tmp_path: Path, text: str, name: str = "tasks.csv") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def _cells(arr: np.ndarray) -> set[tuple[int, int]]:
    return {(int(x), int(y)) for x, y in arr}


# ----------------------------------------------------------------- determinism


@pytest.mark.parametrize(
    "stream",
    [RandomTasks(), DesignatedTasksConfig().build(), DesignatedTasksConfig(sigma=1.5).build()],
    ids=["random", "designated", "designated-narrow"],
)
def test_random_streams_are_seeded(stream: TaskStream) -> None:
    """Random streams give the same tasks for the same seed and different ones otherwise."""
    layout = ShelvesLayoutConfig().build()
    a = stream.generate(_rng(11), layout, 200)
    b = stream.generate(_rng(11), layout, 200)
    c = stream.generate(_rng(12), layout, 200)
    assert a.shape == (200, 4)
    assert a.dtype == np.int64
    assert np.array_equal(a, b)
    assert not np.array_equal(a, c)


@pytest.mark.parametrize("name", ["poc", "two_task"])
def test_fixed_streams_ignore_seed(name: str) -> None:
    """Fixed task lists are the same whatever the seed (deterministic by construction)."""
    stream = task_option(name).build()
    layout = open_grid(10, 10)
    count = 5 if name == "poc" else 7
    a = stream.generate(_rng(1), layout, count)
    b = stream.generate(_rng(2), layout, count)
    assert np.array_equal(a, b)
    if name == "poc":
        assert a.tolist() == [list(t) for t in POC_TASKS]
    else:
        assert a.tolist() == [list(TWO_TASKS[i % 2]) for i in range(7)]
        assert stream.refill_same_slot
        assert stream.max_tasks is None


# ----------------------------------------------------------------- random


def test_random_tasks_on_main_region() -> None:
    """Random origins and destinations lie in the largest region and never coincide."""
    layout = Layout(TWO_REGIONS)
    tasks = RandomTasks().generate(_rng(0), layout, 500)
    main = _cells(layout.main_cells)
    assert _cells(tasks[:, :2]) <= main
    assert _cells(tasks[:, 2:]) <= main
    assert (tasks[:, :2] != tasks[:, 2:]).any(axis=1).all()
    # With only 9 cells, 500 draws use every one of them.
    assert _cells(tasks[:, :2]) == main


def test_random_tasks_need_two_cells() -> None:
    """A layout with a single free cell cannot hold a task with distinct ends."""
    layout = Layout(np.array([[False, True]]))
    with pytest.raises(ConfigError, match="at least 2 free cells"):
        RandomTasks().generate(_rng(0), layout, 3)


# ----------------------------------------------------------------- designated


def _mean_nearest_centre(cells: np.ndarray, centres: np.ndarray) -> float:
    d = np.hypot(*(cells[:, None, :] - centres[None, :, :]).transpose(2, 0, 1))
    return float(d.min(axis=1).mean())


def test_designated_tasks_cluster_near_centres() -> None:
    """Designated tasks lie on free main-region cells, have distinct ends, and sit much closer
    to the centres than uniform random tasks; every centre is used."""
    layout = ShelvesLayoutConfig().build()
    centres = np.array(DEFAULT_CENTRES, dtype=float)
    tasks = DesignatedTasksConfig(sigma=2.0).build().generate(_rng(3), layout, 1000)
    main = _cells(layout.main_cells)
    assert _cells(tasks[:, :2]) <= main
    assert _cells(tasks[:, 2:]) <= main
    assert (tasks[:, :2] != tasks[:, 2:]).any(axis=1).all()
    uniform = RandomTasks().generate(_rng(3), layout, 1000)
    designated_mean = _mean_nearest_centre(tasks[:, :2], centres)
    uniform_mean = _mean_nearest_centre(uniform[:, :2], centres)
    assert designated_mean < 4.0
    assert uniform_mean > 8.0
    assert _mean_nearest_centre(tasks[:, 2:], centres) < 4.0
    nearest = np.hypot(*(tasks[:, None, :2] - centres[None]).transpose(2, 0, 1)).argmin(axis=1)
    assert set(nearest.tolist()) == set(range(len(centres)))


def test_designated_separate_pickup_and_delivery_centres() -> None:
    """Pickups gather around the pickup centre and deliveries around the delivery centre."""
    stream = DesignatedTasks(pickup_centres=[(5, 5)], delivery_centres=[(25, 15)], sigma=1.0)
    tasks = stream.generate(_rng(0), open_grid(30, 20), 300)
    assert np.abs(tasks[:, :2].mean(axis=0) - (5, 5)).max() < 0.5
    assert np.abs(tasks[:, 2:].mean(axis=0) - (25, 15)).max() < 0.5


@pytest.mark.parametrize("key", ["pickup_centres", "delivery_centres"])
def test_designated_centre_outside_grid(key: str) -> None:
    """A centre outside the layout is a ConfigError naming the centre and the grid size."""
    centres = {"pickup_centres": [(3, 3)], "delivery_centres": [(3, 3)], key: [(3, 3), (70, 2)]}
    stream = DesignatedTasksConfig(**centres).build()
    kind = key.split("_")[0]
    with pytest.raises(ConfigError, match=rf"designated {kind} centre \(70, 2\) is outside.*10x10"):
        stream.generate(_rng(0), open_grid(10, 10), 5)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"sigma": 0.0}, "sigma must be > 0"),
        ({"sigma": float("nan")}, "sigma must be a finite number"),
        ({"sigma": float("inf")}, "sigma must be a finite number"),
        ({"pickup_centres": []}, "pickup_centres"),
        ({"delivery_centres": [(1, 2, 3)]}, "delivery_centres"),
    ],
)
def test_designated_rejects_bad_parameters(kwargs: dict[str, object], match: str) -> None:
    """Bad sigma or centre lists are ConfigErrors naming the key."""
    with pytest.raises(ConfigError, match=match):
        DesignatedTasksConfig(**kwargs).build()  # type: ignore[arg-type]


# ----------------------------------------------------------------- fixed / CSV


def test_load_task_csv_good_file(tmp_path: Path) -> None:
    """A CSV with header, spaces and blank lines loads its rows in order."""
    path = _write(tmp_path, "OX, oy ,dx,dy\n1,2,3,4\n\n 5 ,6,7,8\n")
    stream = load_task_csv(path)
    assert isinstance(stream, FixedTasks)
    assert stream.tasks.tolist() == [[1, 2, 3, 4], [5, 6, 7, 8]]
    assert stream.max_tasks == 2
    assert stream.generate(_rng(0), open_grid(10, 10), 2).tolist() == [[1, 2, 3, 4], [5, 6, 7, 8]]


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ("ox,oy,dx\n1,2,3\n", "header 'ox,oy,dx,dy'"),
        ("", "header 'ox,oy,dx,dy'"),
        ("1,2,3,4\n", "header 'ox,oy,dx,dy'"),
        ("ox,oy,dx,dy\n1,2,3,4\n1,2,x,4\n", r":3: expected 4 integers"),
        ("ox,oy,dx,dy\n1,2,3.5,4\n", r":2: expected 4 integers"),
        ("ox,oy,dx,dy\n1,2,3\n", r":2: expected 4 integers"),
        ("ox,oy,dx,dy\n1,2,3,4,5\n", r":2: expected 4 integers"),
        ("ox,oy,dx,dy\n\n", "no tasks"),
    ],
)
def test_load_task_csv_malformed(tmp_path: Path, text: str, match: str) -> None:
    """Malformed task files raise TaskFileError naming the file (and line, for bad rows)."""
    path = _write(tmp_path, text)
    with pytest.raises(TaskFileError, match=match) as info:
        load_task_csv(path)
    assert "tasks.csv" in str(info.value)


def test_load_task_csv_missing(tmp_path: Path) -> None:
    """A missing task file is a TaskFileError naming the path."""
    with pytest.raises(TaskFileError, match=r"not found: .*absent\.csv"):
        load_task_csv(tmp_path / "absent.csv")


def test_fixed_tasks_errors() -> None:
    """FixedTasks rejects bad rows, too many requested tasks and tasks on blocked cells."""
    with pytest.raises(TaskFileError, match="non-empty list"):
        FixedTasks([])
    with pytest.raises(TaskFileError, match="non-empty list"):
        FixedTasks([(1, 2, 3)])
    with pytest.raises(TaskFileError, match="integers"):
        FixedTasks([(1, 2, 3, 4.5)])
    stream = FixedTasks(POC_TASKS, name="poc tasks")
    with pytest.raises(ConfigError, match="poc tasks holds 5 tasks but the episode needs 7"):
        stream.generate(_rng(0), open_grid(10, 10), 7)
    with pytest.raises(LayoutError, match=r"origin of task 0 at \(x=2, y=9\) is outside"):
        stream.generate(_rng(0), open_grid(8, 8), 3)
    grid = np.zeros((10, 10), dtype=bool)
    grid[1, 7] = True
    with pytest.raises(
        LayoutError, match=r"destination of task 4 at \(x=7, y=1\) is on an obstacle"
    ):
        stream.generate(_rng(0), Layout(grid), 5)


# ----------------------------------------------------------------- registry


def test_make_task_stream_builds_streams(tmp_path: Path) -> None:
    """Names, mappings with parameters and objects all give task streams."""
    assert isinstance(task_option("random").build(), RandomTasks)
    designated = task_option({"name": "designated", "sigma": 2.5}).build()
    assert isinstance(designated, DesignatedTasks)
    assert designated.sigma == 2.5
    obj = RandomTasks()
    assert task_option(obj).build() is obj
    csv_path = _write(tmp_path, "ox,oy,dx,dy\n0,0,1,1\n")
    stream = task_option({"name": "file", "path": str(csv_path)}).build()
    assert isinstance(stream, FixedTasks)
    assert stream.tasks.tolist() == [[0, 0, 1, 1]]


@pytest.mark.parametrize(
    ("spec", "match"),
    [
        (
            "uniform",
            "unknown tasks 'uniform'; available: clustered, designated, file, lorr, poc, "
            "random, stations, two_task",
        ),
        (
            {"name": "nope"},
            "available: clustered, designated, file, lorr, poc, random, stations, two_task",
        ),
        ({"sigma": 2.0}, "needs a 'name'"),
        (
            {"name": "random", "sigma": 2.0},
            r"unknown key tasks\.sigma for tasks=random; valid keys: none",
        ),
        (
            {"name": "designated", "centers": [(1, 1)]},
            r"unknown key tasks\.centers .*valid keys: pickup_centres, delivery_centres, sigma",
        ),
        ({"name": "file"}, r"tasks=file needs tasks\.path=\.\.\."),
        ({"name": "file", "path": None}, r"tasks=file needs tasks\.path=\.\.\."),
    ],
)
def test_make_task_stream_errors(spec: object, match: str) -> None:
    """Unknown names and parameters fail with ConfigError listing what exists."""
    with pytest.raises(ConfigError, match=match):
        task_option(spec).build()  # type: ignore[arg-type]


def test_make_layout_builds_layouts(tmp_path: Path) -> None:
    """Layout specs: a name, a mapping with parameters, a file path or a Layout object."""
    assert layout_option("open").build().obstacles.shape == (60, 60)
    assert layout_option({"name": "open", "width": 5, "height": 4}).build().obstacles.shape == (
        4,
        5,
    )
    shelves = layout_option({"name": "shelves", "width": 30, "height": 20, "aisle": 3}).build()
    assert np.array_equal(
        shelves.obstacles, ShelvesLayoutConfig(width=30, height=20, aisle=3).build().obstacles
    )
    path = tmp_path / "g.txt"
    path.write_text(".@\n..\n")
    assert layout_option(str(path)).build().obstacles.tolist() == [[False, True], [False, False]]
    assert layout_option({"name": "open", "path": str(path)}).build().name == "g"
    assert layout_option({"name": "file", "path": str(path)}).build().name == "g"
    grid = open_grid(3, 3)
    assert layout_option(grid).build() is grid


@pytest.mark.parametrize(
    ("spec", "match", "error"),
    [
        (
            "maze",
            "unknown layout 'maze'; available: A, B, C, D, E, file, lorr, open, preset, shelves, "
            "warehouse",
            ConfigError,
        ),
        ("file", r"layout=file needs layout\.path=\.\.\.", ConfigError),
        (
            {"name": "maze"},
            "available: A, B, C, D, E, file, lorr, open, preset, shelves",
            ConfigError,
        ),
        ({"width": 5}, "needs a 'name'", ConfigError),
        (
            {"name": "shelves", "rows": 3},
            r"unknown key layout\.rows for layout=shelves; valid keys: path, width, height, "
            "shelf_width, shelf_height, aisle, margin",
            ConfigError,
        ),
        ({"name": "file"}, r"layout=file needs layout\.path=\.\.\.", ConfigError),
        ("missing.map", "layout file not found", LayoutError),
    ],
)
def test_make_layout_errors(spec: object, match: str, error: type[Exception]) -> None:
    """Unknown layout names and parameters fail and list the alternatives."""
    with pytest.raises(error, match=match):
        layout_option(spec).build()  # type: ignore[arg-type]
