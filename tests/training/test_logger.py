"""``logger=csv`` (the default): one CSV file, a header row, one row per logged step,
columns that never move; and the logger options' errors."""

from __future__ import annotations

import csv
import math
import sys
from pathlib import Path

import pytest

from rtaw_marl.config.store import CONF_DIR
from rtaw_marl.errors import ConfigError
from rtaw_marl.training.checkpoints import trim_csv_logs
from rtaw_marl.training.loggers import (
    LOGGERS,
    METRICS_CSV,
    CSVMetrics,
    build_logger,
    check_installed,
    read_metrics,
)
from rtaw_marl.training.loggers.config import (
    LOGGER_OPTIONS,
    CSVLoggerConfig,
    MLflowLoggerConfig,
    WandbLoggerConfig,
)
from rtaw_marl.training.ppo import train

pytestmark = pytest.mark.unit

#: The paper's proof of concept, two PPO batches of 256 decisions after a four-round
#: imitation warm start, evaluated at 0, 256 and 512 frames.
TINY = [
    "scenario=poc", "frames=512", "selection.every_frames=256", "algo.frames_per_batch=256",
    "algo.minibatch_size=128", "algo.epochs=1", "collector.envs_per_worker=4",
    "selection.seeds=[1000]", "imitation.teacher=lookahead", "imitation.frames=64",
    "imitation.rounds=4",
]  # fmt: skip

#: What every PPO iteration logs: its update's diagnostics beside the losses.
UPDATE = [
    "losses/objective", "losses/critic", "losses/entropy", "losses/approx_kl",
    "losses/clip_fraction", "train/reward_mean", "train/entropy_coeff", "charts/fps",
]  # fmt: skip


def _table(path: Path) -> tuple[list[str], list[dict[str, str]]]:
    with path.open(newline="") as fh:
        reader = csv.DictReader(fh)
        return list(reader.fieldnames or []), list(reader)


def test_a_training_run_writes_one_csv_with_a_row_per_step(train_cfg, tmp_path: Path) -> None:
    result = train(train_cfg(TINY), tmp_path)
    files = [p for p in (tmp_path / "logs").rglob("*") if p.is_file()]
    assert files == [tmp_path / METRICS_CSV]
    columns, rows = _table(tmp_path / METRICS_CSV)
    assert columns[0] == "frames"
    assert len(columns) == len(set(columns))
    assert set(UPDATE) | {"eval/ttd", "eval/mpdm_ttd", "imitation/loss"} <= set(columns)
    # The warm start's four rounds at frame 0 on their own axis, then one row per step:
    # the frame-0 evaluation, then each iteration's update with its evaluation.
    assert [int(r["frames"]) for r in rows] == [0, 0, 0, 0, 0, 256, 512]
    assert [r["imitation/decisions"] for r in rows[:4]] == ["16.0", "32.0", "48.0", "64.0"]
    for row in rows[5:]:
        assert all(math.isfinite(float(row[name])) for name in UPDATE), row
        assert 0.0 <= float(row["losses/clip_fraction"]) <= 1.0
    ttds = [(r["frames"], r["eval/ttd"]) for r in read_metrics(tmp_path / METRICS_CSV, "eval/ttd")]
    assert ttds == [(h["frames"], h["ttd"]) for h in result.history]
    assert not any(rows[4][name] for name in UPDATE)  # frame 0: evaluated, not updated


def test_a_scalar_first_seen_later_adds_a_column_and_keeps_every_row(tmp_path: Path) -> None:
    path = tmp_path / "logs" / "metrics.csv"
    metrics = CSVMetrics(path)
    metrics.log({"a": 1.0}, 10)
    metrics.log({"b": 2.0}, 10)  # the same step, another scalar: the same row
    metrics.log({"a": 3.0}, 20)
    metrics.log({"a": 4.0}, 20)  # a repeated name: a new row, never overwritten
    metrics.log({"c": 5.0, "a": 6.0}, 30)
    columns, rows = _table(path)
    assert columns == ["frames", "a", "b", "c"]
    assert [list(r.values()) for r in rows] == [
        ["10", "1.0", "2.0", ""],
        ["20", "3.0", "", ""],
        ["20", "4.0", "", ""],
        ["30", "6.0", "", "5.0"],
    ]
    assert not list(path.parent.glob(".*tmp"))  # the rewrites were atomic renames
    assert b"\r" not in path.read_bytes()  # plain "\n" lines, appended or rewritten


def test_a_resumed_run_continues_the_file_with_its_columns(tmp_path: Path) -> None:
    path = tmp_path / "metrics.csv"
    first = CSVMetrics(path)
    first.log({"d": 1.0, "ttd": 5.0}, 0, axis="d")
    first.log({"ttd": 4.0}, 512)
    first.log({"ttd": 3.0}, 1024)
    with path.open("a") as fh:
        fh.write("15")  # a line a kill tore
    assert trim_csv_logs(tmp_path, 512) == 2  # 1024's row and the torn line
    again = CSVMetrics(path)
    again.log({"ttd": 2.0, "kl": 0.1}, 1024)
    assert read_metrics(path) == [
        {"frames": 0.0, "d": 1.0, "ttd": 5.0},
        {"frames": 512.0, "ttd": 4.0},
        {"frames": 1024.0, "ttd": 2.0, "kl": 0.1},
    ]
    assert path.read_text().splitlines()[0] == "frames,d,ttd,kl"


def _uninstall(module: str, monkeypatch: pytest.MonkeyPatch) -> None:
    """Imports of ``module`` and its submodules fail as if it were not installed (even
    where another test imported them already)."""
    for name in [m for m in sys.modules if m == module or m.startswith(f"{module}.")]:
        monkeypatch.setitem(sys.modules, name, None)
    monkeypatch.setitem(sys.modules, module, None)


def test_no_logger_writes_nothing(tmp_path: Path) -> None:
    logger = build_logger(tmp_path, "none")
    logger.log({"a": 1.0}, 0)
    logger.close()
    assert not (tmp_path / "logs").exists()


@pytest.mark.parametrize(
    ("name", "package", "module"),
    [("mlflow", "MLflow", "mlflow"), ("wandb", "wandb", "wandb")],
)
def test_a_missing_package_names_its_extra(
    name: str, package: str, module: str, monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    _uninstall(module, monkeypatch)
    with pytest.raises(ConfigError) as caught:
        build_logger(tmp_path, name)
    assert str(caught.value) == (
        f"logger={name} needs {package} (not installed): pip install 'rtaw_marl[{name}]'"
    )


def test_a_missing_package_is_one_error_line_on_the_command_line(
    cli, monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    _uninstall("mlflow", monkeypatch)
    result = cli("train", *TINY, "logger=mlflow", f"output_dir={tmp_path / 'run'}")
    assert result.code == 2
    assert result.err.strip().splitlines() == [
        "error: logger=mlflow needs MLflow (not installed): pip install 'rtaw_marl[mlflow]'"
    ]


@pytest.mark.parametrize(
    ("overrides", "message"),
    [
        (["logger=foo"], "available: csv, mlflow, none, tensorboard, wandb"),
        (["logger=wandb", "logger.mode=live"], "logger.mode must be one of offline, online"),
        (["logger=mlflow", "logger.project=x"], "unknown config key 'logger.project'"),
        (["logger.tracking_uri=x"], "logger=csv takes no keys"),
    ],
)
def test_bad_logger_options_fail_clearly(overrides: list[str], message: str, cli) -> None:
    result = cli("train", "scenario=poc", "frames=1024", *overrides)
    assert result.code == 2
    (line,) = result.err.strip().splitlines()
    assert line.startswith("error: ")
    assert message in line


def test_every_logger_option_has_its_defaults_and_a_name() -> None:
    assert list(LOGGER_OPTIONS) == ["csv", "tensorboard", "none", "mlflow", "wandb"]
    assert all(option().name == name for name, option in LOGGER_OPTIONS.items())
    # No network unless asked: MLflow's store in the run folder, W&B offline.
    assert MLflowLoggerConfig().tracking_uri is None
    assert WandbLoggerConfig().mode == "offline"


def test_the_backend_registry_serves_exactly_the_yaml_logger_options() -> None:
    yaml_options = {path.stem for path in (CONF_DIR / "logger").glob("*.yaml")}
    assert set(LOGGERS) == yaml_options == set(LOGGER_OPTIONS)
    assert all(backend.name == name for name, backend in LOGGERS.items())


@pytest.mark.parametrize("option", ["foo", CSVLoggerConfig(name="foo")])
def test_an_unknown_backend_is_one_error_listing_the_registry(
    option: str | CSVLoggerConfig, tmp_path: Path
) -> None:
    message = "unknown logger 'foo'; available: csv, mlflow, none, tensorboard, wandb"
    for call in (lambda: build_logger(tmp_path, option), lambda: check_installed(option)):
        with pytest.raises(ConfigError) as caught:
            call()
        assert str(caught.value) == message
    assert not (tmp_path / "logs").exists()
