"""The one LoRR problem reader: every damaged problem is one line naming the file and
the key, before any work; the start kit's reveal window; the cases LoRR allows."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from rtaw_marl.errors import ConfigError, TaskFileError
from rtaw_marl.evaluation.evaluate import run_episode
from rtaw_marl.policies import make_baseline
from rtaw_marl.scenarios import lorr_scenario
from rtaw_marl.sim.builder import build_sim
from rtaw_marl.sim.lorr import read_problem, reveal_window
from tests.sim.test_lorr import write_problem

pytestmark = pytest.mark.unit


def problem(root: Path, tasks: str = "2\n1,7\n4,0\n", agents: str = "2\n0\n7\n",
            **keys: object) -> Path:  # fmt: skip
    """test_lorr's 4x2 problem (map '....' / '..@.', location = row * 4 + col) in ``root``."""
    root.mkdir(parents=True, exist_ok=True)
    return write_problem(root, tasks, agents, **keys)


@pytest.mark.parametrize(
    ("tasks", "agents", "keys", "message"),
    [
        ("0\n", "2\n0\n7\n", {}, r"t\.tasks: holds no task"),
        ("2\n1,7\n4,0\n", "2\n0\n0\n", {}, r"robots 0 and 1 start on the same location 0 "),
        ("2\n1,7\n4,0\n", "2\n0\n6\n", {}, r"start of robot 1 at \(x=2, y=1\) is on an obstacle"),
        ("2\n1,7\n4,0\n", "2\n0\n7\n", {"teamSize": 3}, r"teamSize 3 is more than the 2 start"),
        ("1\n1,7,2\n", "2\n0\n7\n", {}, r"t\.tasks:2: a task has 3 errands"),
        ("2\n1,7\n4,0\n", "2\n0\n7\n", {"numTasksReveal": float("inf")}, r"finite count"),
        ("2\n1,7\n4,0\n", "2\n0\n7\n", {"numTasksReveal": float("nan")}, r"a number above 1"),
        (
            "2\n1,7\n4,0\n",
            "2\n0\n7\n",
            {"numTasksReveal": 1.0000000001},
            r"reveals 2 tasks to 2 robots .* numTasksReveal >= 1\.5",
        ),
        (
            "2\n1,7\n4,0\n",
            "2\n0\n7\n",
            {"agentFile": "../../etc/passwd"},
            r"agentFile '\.\./\.\./etc/passwd' lies outside the problem's folder",
        ),
        ("2\n1,7\n4,0\n", "2\n0\n7\n", {"mapFile": 5}, r"mapFile must be a file name, got 5"),
    ],
)
def test_a_damaged_problem_is_one_line_naming_file_and_key(
    tmp_path: Path, tasks: str, agents: str, keys: dict, message: str
) -> None:
    path = problem(tmp_path / "p", tasks, agents, **keys)
    with pytest.raises(ConfigError, match=message) as info:
        read_problem(path)
    assert "\n" not in str(info.value)
    assert "np." not in str(info.value)


def test_a_file_outside_the_folder_is_never_opened(tmp_path: Path) -> None:
    """Not even for the message: a problem cannot make the reader echo another file."""
    secret = tmp_path / "secret.agents"
    secret.write_text("top secret line\n")
    path = problem(tmp_path / "p", agentFile="../secret.agents")
    with pytest.raises(TaskFileError) as info:
        read_problem(path)
    assert "top secret" not in str(info.value)


def test_deeply_nested_json_is_one_line(tmp_path: Path) -> None:
    path = tmp_path / "deep.json"
    path.write_text("[" * 200_000 + "]" * 200_000)
    with pytest.raises(TaskFileError, match="nested too deeply"):
        read_problem(path)


def test_a_symlinked_problem_reads_the_folder_of_its_target(tmp_path: Path) -> None:
    """The link is followed first: the reader, rtaw-eval and LoRR's lifelong (given the
    resolved path) all read the target's map, and the problem is recorded as the target."""
    real = problem(tmp_path / "real")
    other = tmp_path / "other"
    other.mkdir()
    (other / "m.map").write_text("type octile\nheight 1\nwidth 2\nmap\n..\n")
    link = other / "p.json"
    link.symlink_to(real)
    read = read_problem(link)
    assert read.path == real.resolve()
    assert read.map_path == (tmp_path / "real" / "m.map").resolve()
    assert read.layout().width == 4


def test_the_window_is_the_start_kits_truncated_product() -> None:
    """LoRR: int num_tasks_reveal = float(numTasksReveal) * teamSize (truncated)."""
    assert reveal_window(1.5, 100) == 150
    assert reveal_window(1.25, 10) == 12
    assert reveal_window(1.5, 5) == 7
    # float32: 1.1f * 10 = 11.000000238..., so 11 (double arithmetic agrees here).
    assert reveal_window(1.1, 10) == 11


def test_the_read_is_cached_until_a_file_changes(tmp_path: Path) -> None:
    path = problem(tmp_path / "p")
    first = read_problem(path)
    assert read_problem(path) is first
    assert not first.tasks.flags.writeable
    (tmp_path / "p" / "t.tasks").write_text("3\n1,7\n4,0\n3,5\n")
    assert len(read_problem(path).tasks) == 3


@pytest.mark.parametrize("navigator", ["pibt", "astar"])
def test_a_task_whose_pickup_is_its_delivery_takes_a_timestep(
    tmp_path: Path, navigator: str
) -> None:
    """LoRR's files hold such tasks; LoRR checks one errand per robot and timestep, so
    each takes at least a timestep: 2 robots finish at most 2 per timestep (before: the
    whole pool at t = 0)."""
    path = problem(tmp_path / "p", tasks="2\n0,0\n7,7\n", teamSize=2, numTasksReveal=2)
    sim = build_sim(lorr_scenario(path, navigator=navigator, horizon=20).spec())
    run_episode(sim, make_baseline("mpdm"), seed=0)
    finished = sim.metrics().tasks_finished
    assert 0 < finished <= 2 * 20


def test_a_bad_horizon_is_named(tmp_path: Path) -> None:
    path = problem(tmp_path / "p")
    with pytest.raises(ConfigError, match=r"sim\.horizon must be >= 1, got -5"):
        lorr_scenario(path, horizon=-5)
    with pytest.raises(ConfigError, match=r"sim\.num_robots must be >= 1, got 0"):
        lorr_scenario(path, num_robots=0)
    assert np.isfinite(read_problem(path).mean_task_length())
