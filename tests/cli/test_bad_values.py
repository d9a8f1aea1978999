"""Bad values, one battery: each is one ``error: ...`` line on stderr naming the problem,
exit status 2, no traceback, and nothing silently clipped, truncated or "fixed".

Every case runs in-process (the ``cli`` fixture runs the console entry points' ``main``;
Python-API cases go through the same conversion of a user error into one line and
status 2), and each error is raised before any expensive work, so the file takes
seconds. The few files the cases need are written into ``tmp_path``.
"""

from __future__ import annotations

import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from rtaw_marl.config import compose, to_typed
from rtaw_marl.errors import LayoutError, RtawError, TaskFileError
from rtaw_marl.evaluation import evaluate
from rtaw_marl.evaluation.config import EvalConfig
from rtaw_marl.sim.builder import SimSpec, build_sim
from rtaw_marl.sim.config import SimConfig
from rtaw_marl.sim.layout import open_grid
from rtaw_marl.sim.tasks import FixedTasks, load_task_csv
from rtaw_marl.training.config import CollectorConfig, PPOConfig, TrainConfig
from tests.conftest import CliResult

pytestmark = pytest.mark.integration

#: A 7x7 ASCII map whose cell (5, 5) is walled in by shelves.
WALLED = "\n".join([".......", ".......", ".......", ".......", "....@@@", "....@.@", "....@@@"])

#: Files the cases name as ``{tmp}/NAME``.
FILES: dict[str, bytes] = {
    "binary.csv": b"\xff\xfe\x00\x01\x89PNG\r\n\x1a\n" + bytes(range(256)),
    "long.csv": b"ox,oy,dx,dy\n" + b"1" * 200_000 + b",1,2,2\n",
    "bom.csv": b"\xef\xbb\xbfox,oy,dx,dy\n1,1,2,2\n",
    "huge.csv": b"ox,oy,dx,dy\n99999999999999999999999,1,2,2\n",
    "walled.txt": WALLED.encode() + b"\n",
    # The walled-in task comes first: the message must still blame (5, 5), not (1, 1).
    "walled.csv": b"ox,oy,dx,dy\n5,5,2,2\n1,1,0,0\n3,3,1,0\n",
    "agents.scen": b"version 1\n0\tmap.map\t8\t8\t1\t1\t2\t2\t1.0\n",
    "layout.json": b'{"width": 4, "height": 4}\n',
    "LICENSE": b"....\n....\n",
}

#: Arguments every case of an app starts with (a small scenario; no progress bar, which
#: would write to stderr).
BASE = {
    "eval": ["scenario=poc", "progress=false"],
    "train": ["scenario=poc", "progress=false"],
    "render": ["scenario=poc"],
    "view": ["scenario=poc"],
}

#: What an old ``env`` key's line says after the new key (``env`` -> ``sim``).
SIM_RENAMED = "(the simulator's keys; env names the PettingZoo env)"

_WALLED_RUN = [
    "layout.path={tmp}/walled.txt",
    "tasks=file",
    "tasks.path={tmp}/walled.csv",
    "navigator=astar",
    "sim.num_tasks=3",
]

#: (app, overrides, what the message must contain).
CLI_CASES: list[tuple[str, list[str], str]] = [
    # Task files.
    ("eval", ["tasks=file", "tasks.path={tmp}/binary.csv"], "binary.csv: not a UTF-8 text file"),
    ("eval", ["tasks=file", "tasks.path={tmp}/long.csv"], "field larger than field limit (131072)"),
    (
        "eval",
        ["tasks=file", "tasks.path={tmp}/huge.csv"],
        "huge.csv:2: coordinate 99999999999999999999999 is out of range",
    ),
    # Robot starts.
    ("eval", ["sim.robot_starts=[[a,0],[0,0]]"], "sim.robot_starts[0]': Value 'a'"),
    ("eval", ["sim.robot_starts=5"], "config key 'sim.robot_starts'"),
    ("eval", ["sim.robot_starts=[[inf,0],[0,0]]"], "sim.robot_starts[0]': Value inf"),
    ("eval", ["sim.robot_starts=[[1.5,0],[0,0]]"], "sim.robot_starts[0]': Value 1.5"),
    (
        "eval",
        ["navigator=sipp", "sim.robot_starts=[[1,1],[1,1]]"],
        "robots 0 and 1 both start at (x=1, y=1)",
    ),
    ("eval", ["sim.robot_free_times=[nan,0]"], "sim.robot_free_times[0] must be a finite number"),
    # Seeds.
    ("eval", ["seeds=[0,-1]"], "seeds[1] must be an integer >= 0, got -1"),
    ("eval", ["seeds=-3"], "seeds must be an integer >= 0, got -3"),
    # One episode counted three times would be "significant".
    ("eval", ["seeds=[0,0,0]"], "seeds lists a seed more than once: 0 (3 times); each seed"),
    ("eval", ["seeds=[4,1,4,1]"], "seeds lists a seed more than once: 4 (2 times), 1 (2 times)"),
    # A policy named twice was merged silently: it ran once, under one label.
    ("eval", ["policy=[mpdm,mpdm]"], "two policies are labelled 'mpdm'"),
    (
        "eval",
        ["policy=pretrained", "pretrained=[generalist,generalist]"],
        "pretrained= names 'generalist' twice",
    ),
    (
        "eval",
        ["scenario=lorr", "tasks.problem=builtin:random_32_32_20_100.json", "sim.horizon=-5"],
        "sim.horizon must be >= 1, got -5",
    ),
    # Hydra's grammar reads unquoted values as ASCII: the line shows the quoted form.
    (
        "eval",
        ["layout.path=/tmp/ü/map.txt"],
        """cannot parse the override 'layout.path=/tmp/ü/map.txt': a value with non-ASCII """
        """characters must be quoted, e.g. 'layout.path="/tmp/ü/map.txt"'""",
    ),
    ("train", ["seed=-1"], "seed must be an integer >= 0, got -1"),
    ("train", ["selection.seeds=[-1]"], "selection.seeds[0] must be an integer >= 0, got -1"),
    ("train", ["selection.seeds=[]"], "selection.seeds must name at least one seed"),
    (
        "train",
        ["selection.seeds=[1000,3]"],
        "selection.seeds [3] are below 1000: selection seeds start at 1000; seeds 0-999 are kept "
        "for evaluation, which must not choose checkpoints",
    ),
    ("render", ["seed=-1"], "seed must be an integer >= 0, got -1"),
    # Renamed keys: the old name says the new one (not "unknown key"), in a sweep too.
    *[
        (
            "train",
            old,
            f"eval.{key} is now selection.{key} (the selection seeds' evaluation during training)",
        )
        for old, key in [
            (["eval.every_frames=1024"], "every_frames"),
            (["+eval.keep=2"], "keep"),
            (["--multirun", "eval.seeds=[1000],[1001]"], "seeds"),
        ]
    ],
    # The simulator's group was env: in every command with it, the old key names the new.
    *[
        (app, old, f"{key} is now {new} {SIM_RENAMED}")
        for app in ("eval", "train", "render", "view")
        for old, key, new in [
            (["env.num_robots=50"], "env.num_robots", "sim.num_robots"),
            (["+env.horizon=500"], "env.horizon", "sim.horizon"),
            (["~env.noise_var"], "env.noise_var", "sim.noise_var"),
            (["env=default"], "env", "sim"),
        ]
    ],
    (
        "eval",
        ["--multirun", "env.num_robots=10,100"],
        f"env.num_robots is now sim.num_robots {SIM_RENAMED}",
    ),
    (
        "train",
        ["--multirun", "env.queue_len=5,10"],
        f"env.queue_len is now sim.queue_len {SIM_RENAMED}",
    ),
    # Numbers that are not numbers, or not integers.
    ("eval", ["layout.width=nan"], "config key 'layout.width': Value 'nan'"),
    ("eval", ["layout.width=10.7"], "config key 'layout.width': Value '10.7'"),
    ("train", ["frames=nan"], "config key 'frames': Value 'nan'"),
    ("train", ["algo.lr=nan"], "algo.lr must be a finite number, got nan"),
    ("train", ["algo.clip_epsilon=inf"], "algo.clip_epsilon must be a finite number, got inf"),
    ("train", ["algo.gamma=1.5"], "algo.gamma must lie in [0, 1], got 1.5"),
    ("train", ["algo.reward_scale=-1"], "algo.reward_scale must be > 0"),
    ("train", ["imitation.lr=inf"], "imitation.lr must be a finite number, got inf"),
    ("eval", ["sim.noise_var=inf"], "sim.noise_var must be a finite number, got inf"),
    ("eval", ["sim.noise_mean=-100"], "sim.noise_mean must be >= 0, got -100"),
    ("eval", ["tasks=designated", "tasks.sigma=inf"], "tasks.sigma must be a finite number"),
    (
        "eval",
        ["tasks=designated", "tasks.pickup_centres=[[1,2,3]]"],
        "tasks.pickup_centres must be a non-empty list of [x, y] pairs",
    ),
    ("eval", ["tasks=designated", "tasks.delivery_centres=[]"], "non-empty list of [x, y]"),
    (
        "eval",
        ["tasks=designated", "tasks.pickup_centres=[[nan,1.0]]"],
        "tasks.pickup_centres[0][0] must be a finite number, got nan",
    ),
    (
        "eval",
        ["navigator=sipp", "navigator.time_limit=inf"],
        "navigator.time_limit must be a positive number, got inf",
    ),
    # Booleans take true or false, nothing else.
    ("eval", ["lower_bound=off"], "lower_bound must be true or false, got 'off'"),
    ("eval", ["progress=off"], "progress must be true or false, got 'off'"),
    ("train", ["interop=yes"], "interop must be true or false, got 'yes'"),
    ("train", ["algo.normalize_advantage=1"], "algo.normalize_advantage must be true or false"),
    # Sizes nothing could hold: refused up front with the estimate.
    ("eval", ["sim.num_tasks=1000000000000"], "this simulator needs ~232.8 TiB of memory"),
    ("eval", ["sim.queue_len=1000000000", "navigator=astar"], "needs ~96.9 GiB of memory"),
    ("eval", ["layout.width=100000", "layout.height=100000"], "layout open 100000x100000"),
    # Layouts.
    ("eval", _WALLED_RUN, "origin of task 0 at (x=5, y=5) cannot be reached"),
    ("eval", ["layout.path={tmp}/agents.scen"], "unknown layout format '.scen'; known: .cfg"),
    ("eval", ["layout.path={tmp}/layout.json"], "unknown layout format '.json'; known: .cfg"),
    ("eval", ["layout.path={tmp}/LICENSE"], "unknown layout format '(no extension)'"),
    ("eval", ["layout=shelves", "layout.aisle=0"], "layout.aisle must be >= 1, got 0"),
    ("eval", ["tasks=clustered", "tasks.num_clusters=0"], "tasks.num_clusters must be >= 1"),
    ("eval", ["navigator=direct", "+navigator.time_limit=5"], "navigator=direct takes no keys"),
    ("eval", ["navigator=direct", "navigator.time_limit=5"], "navigator=direct takes no keys"),
    # Counts that must be positive.
    ("train", ["collector.workers=0"], "collector.workers must be >= 1, got 0"),
    ("train", ["collector.envs_per_worker=0"], "collector.envs_per_worker must be >= 1, got 0"),
    ("train", ["algo.minibatch_size=0"], "algo.minibatch_size must be >= 1, got 0"),
    ("train", ["selection.every_frames=0"], "selection.every_frames must be >= 1, got 0"),
    ("train", ["torch_threads=0"], "torch_threads must be >= 1, got 0"),
    (
        "train",
        ["logger=foo"],
        "Could not find 'logger/foo'; available: csv, mlflow, none, tensorboard, wandb",
    ),
    ("eval", ["torch_threads=0"], "torch_threads must be >= 1, got 0"),
    ("render", ["torch_threads=0"], "torch_threads must be >= 1, got 0"),
    ("render", ["fps=0"], "fps must be >= 1, got 0"),
    ("render", ["every=0"], "every must be >= 1, got 0"),
]


def _groups(**sim: Any) -> dict[str, Any]:
    """The four simulator groups of a run config, as the Python API takes them."""
    return {"sim": sim, "layout": "open", "navigator": "direct", "tasks": "poc"}


#: (name, a call through the Python API, what the message must contain).
PYTHON_CASES: list[tuple[str, Callable[[], object], str]] = [
    (
        "robot_starts_float",
        lambda: SimConfig(num_robots=2, robot_starts=[[1.5, 0], [0, 0]]),
        "sim.robot_starts[0][0] must be an integer, got 1.5",
    ),
    (
        "robot_starts_int",
        lambda: SimConfig(num_robots=2, robot_starts=5),  # type: ignore[arg-type]
        "sim.robot_starts must be a list, got 5",
    ),
    (
        "robot_starts_str",
        lambda: SimConfig(num_robots=2, robot_starts=[["a", 0], [0, 0]]),  # type: ignore[list-item]
        "sim.robot_starts[0][0] must be an integer, got 'a'",
    ),
    (
        "robot_starts_huge",
        lambda: SimConfig(num_robots=2, robot_starts=[[10**22, 0], [0, 0]]),
        "sim.robot_starts: coordinate 10000000000000000000000 is out of range",
    ),
    (
        "num_robots_float",
        lambda: SimConfig(num_robots=2.0),  # type: ignore[arg-type]
        "sim.num_robots must be an integer, got 2.0",
    ),
    (
        "layout_width_float",
        lambda: SimSpec.of(layout={"name": "open", "width": 10.7}),
        "layout.width must be an integer, got 10.7",
    ),
    ("open_grid_float", lambda: open_grid(10.7, 10), "layout.width must be an integer, got 10.7"),  # type: ignore[arg-type]
    (
        "lower_bound_string",
        lambda: EvalConfig(**_groups(), lower_bound="off"),  # type: ignore[arg-type]
        "lower_bound must be true or false, got 'off'",
    ),
    (
        "progress_string",
        lambda: EvalConfig(**_groups(), progress="off"),  # type: ignore[arg-type]
        "progress must be true or false, got 'off'",
    ),
    (
        "eval_seed_float",
        lambda: EvalConfig(**_groups(), seeds=[0, 1.5]),
        "seeds[1] must be an integer >= 0, got 1.5",
    ),
    (
        "eval_seeds_repeated",
        lambda: EvalConfig(**_groups(), seeds=[3, 3]),
        "seeds lists a seed more than once: 3 (2 times)",
    ),
    (
        "evaluate_seeds_repeated",
        lambda: evaluate(build_sim(SimSpec.of()), {}, [7, 7]),
        "seeds lists a seed more than once: 7 (2 times)",
    ),
    (
        "frames_nan",
        lambda: TrainConfig(**_groups(), model={}, frames=float("nan")),  # type: ignore[arg-type]
        "frames must be an integer, got nan",
    ),
    ("lr_nan", lambda: PPOConfig(lr=float("nan")), "algo.lr must be a finite number, got nan"),
    ("workers_zero", lambda: CollectorConfig(workers=0), "collector.workers must be >= 1, got 0"),
    (
        "task_coordinate_huge",
        lambda: FixedTasks([[99999999999999999999999, 1, 2, 2]]),
        "coordinate 99999999999999999999999 is out of range",
    ),
    (
        "task_coordinate_nan",
        lambda: FixedTasks([[float("nan"), 1, 2, 2]]),
        "task coordinates must be integers",
    ),
]


def _python(call: Callable[[], object], capsys: pytest.CaptureFixture[str]) -> CliResult:
    """Run ``call`` as the CLIs run their task: a user error becomes ``error: <its one
    line>`` on stderr and exit status 2 (``exit_on_user_error``, without Hydra)."""
    capsys.readouterr()
    try:
        call()
        code = 0
    except RtawError as exc:
        print(f"error: {exc}", file=sys.stderr)
        code = 2
    captured = capsys.readouterr()
    return CliResult(code, captured.out, captured.err)


def _assert_one_line_error(result: CliResult, message: str) -> None:
    assert result.code == 2, (result.out, result.err)
    lines = [line for line in result.err.splitlines() if line.strip()]
    assert len(lines) == 1, result.err
    assert lines[0].startswith("error: "), lines[0]
    assert message in lines[0], lines[0]
    assert "Traceback" not in result.err + result.out


@pytest.fixture
def files(tmp_path: Path) -> Path:
    """The cases' input files, in a folder of their own."""
    folder = tmp_path / "inputs"
    folder.mkdir()
    for name, data in FILES.items():
        (folder / name).write_bytes(data)
    return folder


@pytest.fixture
def small_memory(monkeypatch: pytest.MonkeyPatch) -> None:
    """A 16 GiB machine, whatever this one has: the memory cases do not depend on it."""
    monkeypatch.setattr("rtaw_marl.sim.budget.memory_limit", lambda: 16 * 2**30)


@pytest.mark.parametrize(
    ("app", "overrides", "message"),
    CLI_CASES,
    ids=[f"{app}:{' '.join(args)}" for app, args, _ in CLI_CASES],
)
def test_bad_value_on_the_command_line(
    app: str, overrides: list[str], message: str, cli, files: Path, small_memory: None
) -> None:
    """``rtaw-<app> <overrides>``: one ``error:`` line naming the problem, exit 2."""
    args = [*BASE[app], *(o.format(tmp=files) for o in overrides)]
    if app == "train":
        args.append(f"output_dir={files.parent / 'run'}")
    _assert_one_line_error(cli(app, *args), message)


@pytest.mark.parametrize(
    ("call", "message"),
    [case[1:] for case in PYTHON_CASES],
    ids=[case[0] for case in PYTHON_CASES],
)
def test_bad_value_through_the_python_api(
    call: Callable[[], object], message: str, capsys: pytest.CaptureFixture[str]
) -> None:
    """The same rules hold for configs built in Python, which Hydra never typed."""
    _assert_one_line_error(_python(call, capsys), message)


@pytest.mark.parametrize("name", ["binary.csv", "long.csv", "huge.csv"])
def test_bad_task_file_is_a_task_file_error(name: str, files: Path) -> None:
    """A task file that is not one is a one-line TaskFileError naming the file."""
    with pytest.raises(TaskFileError) as info:
        load_task_csv(files / name)
    assert name in str(info.value)
    assert "\n" not in str(info.value)


# ----------------------------------------------------------------- what still works


def test_task_csv_with_a_byte_order_mark_loads(files: Path, cli) -> None:
    """A BOM (as spreadsheet programs write) is not part of the header: the file loads,
    by itself and through rtaw-eval."""
    assert load_task_csv(files / "bom.csv").tasks.tolist() == [[1, 1, 2, 2]]
    result = cli(
        "eval",
        *BASE["eval"],
        "tasks=file",
        f"tasks.path={files / 'bom.csv'}",
        "sim.num_tasks=1",
        "policy=[mpdm]",
        "seeds=[0]",
        f"output={files.parent / 'results.json'}",
    )
    assert result.code == 0, result.err


@pytest.mark.parametrize(
    "starts",
    [[[1, 1], [2, 2]], ((1, 1), (2, 2)), np.array([[1, 1], [2, 2]]), [[np.int64(1), 1], [2, 2]]],
    ids=["lists", "tuples", "array", "numpy-ints"],
)
def test_valid_robot_starts_still_work(starts: Any) -> None:
    """Integer starts in any sequence form still build, with a collision-aware navigator."""
    keys = {"num_robots": 2, "num_tasks": 2, "queue_len": 1, "noise_mean": 0, "noise_var": 0}
    spec = SimSpec.of(
        {**keys, "robot_starts": starts}, {"name": "open", "width": 5}, "sipp", "random"
    )
    sim = build_sim(spec)
    sim.reset(0)
    assert sim.robot_start_xy.tolist() == [[1, 1], [2, 2]]


def test_integer_centres_are_numbers(cli) -> None:
    """OmegaConf refuses ints in a nested float list; the schema takes them."""
    result = cli("eval", "tasks=designated", "tasks.pickup_centres=[[10,20]]", "policy=mpdm",
                 "seeds=[0]", "sim.num_tasks=20", "progress=false")  # fmt: skip
    assert result.code == 0, result.err


def test_real_booleans_are_still_booleans() -> None:
    """``true``/``false`` (any case) still compose to booleans."""
    cfg = to_typed(compose("eval", ["scenario=poc", "lower_bound=true", "progress=False"]))
    assert (cfg.lower_bound, cfg.progress) == (True, False)


def test_walled_in_cell_is_blamed_whatever_the_task_order(files: Path) -> None:
    """The cell outside the region the others share is named, whichever task comes first."""
    keys = {"num_robots": 2, "num_tasks": 3, "queue_len": 1}
    for rows, index in (([(1, 1, 0, 0), (5, 5, 2, 2), (3, 3, 1, 0)], 1), ([(5, 5, 2, 2)] * 3, 0)):
        tasks = FixedTasks(rows)
        spec = SimSpec.of(keys, str(files / "walled.txt"), "astar", tasks)
        with pytest.raises(LayoutError, match=rf"origin of task {index} at \(x=5, y=5\)"):
            build_sim(spec).reset(0)
