"""``logger=mlflow`` and ``logger=wandb``: a tiny training run lands in a local MLflow
store and an offline W&B run, with the metrics and the resolved config, no network."""

from __future__ import annotations

import json
import struct
from pathlib import Path
from typing import Any

import pytest
from mlflow.tracking import MlflowClient
from wandb.proto import wandb_internal_pb2

from rtaw_marl.training.loggers.mlflow_log import flat_params
from rtaw_marl.training.ppo import train

pytestmark = pytest.mark.integration

#: The paper's proof of concept: two PPO batches of 256 decisions, evaluated at 0 and 512.
TINY = [
    "scenario=poc", "frames=512", "selection.every_frames=512", "algo.frames_per_batch=256",
    "algo.minibatch_size=128", "algo.epochs=1", "collector.envs_per_worker=4",
    "selection.seeds=[1000]",
]  # fmt: skip


def test_mlflow_run_in_a_local_store_holds_metrics_and_the_config(
    train_cfg, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)  # nothing may land in the working folder
    run_dir = tmp_path / "run"
    result = train(train_cfg([*TINY, "logger=mlflow"]), run_dir)
    client = MlflowClient(tracking_uri=f"sqlite:///{run_dir / 'logs' / 'mlflow.db'}")
    experiment = client.get_experiment_by_name("rtaw_marl")
    (run,) = client.search_runs([experiment.experiment_id])
    assert run.info.run_name == "run"
    assert run.info.status == "FINISHED"
    assert run.data.tags["rtaw.run_dir"] == str(run_dir)
    ttd = client.get_metric_history(run.info.run_id, "eval/ttd")
    assert [(m.step, m.value) for m in ttd] == [(h["frames"], h["ttd"]) for h in result.history]
    for name in ("losses/approx_kl", "losses/clip_fraction", "train/reward_mean"):
        assert [m.step for m in client.get_metric_history(run.info.run_id, name)] == [256, 512]
    params = run.data.params
    assert params["algo.lr"] == str(result_cfg_lr(train_cfg))
    assert params["sim.num_robots"] == "2"
    assert params["selection.seeds"] == "[1000]"
    assert params["logger.name"] == "mlflow"
    assert params["model.name"] == "rtaw"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run"]


def result_cfg_lr(train_cfg) -> float:
    """The learning rate the tiny run resolves to (the parameter's expected value)."""
    return train_cfg(TINY).algo.lr


def test_flat_params_are_dotted_keys_with_json_values() -> None:
    config = {"a": {"b": 1, "c": [1, 2], "d": None, "e": {}}, "f": "x", "g": True}
    assert flat_params(config) == {
        "a.b": "1", "a.c": "[1, 2]", "a.d": "null", "a.e": "{}", "f": "x", "g": "true",
    }  # fmt: skip
    assert flat_params({"s": list(range(5000))})["s"].endswith("...")
    assert len(flat_params({"s": list(range(5000))})["s"]) == 6000


def test_wandb_offline_run_holds_metrics_and_the_config(
    train_cfg, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # W&B's own folders (settings, cache) in tmp_path too; offline needs no account.
    for var in ("WANDB_CONFIG_DIR", "WANDB_CACHE_DIR", "WANDB_DATA_DIR"):
        monkeypatch.setenv(var, str(tmp_path / "wandb-home"))
    monkeypatch.delenv("WANDB_MODE", raising=False)
    monkeypatch.delenv("WANDB_API_KEY", raising=False)
    run_dir = tmp_path / "run"
    result = train(train_cfg([*TINY, "logger=wandb"]), run_dir)
    (offline,) = (run_dir / "logs" / "wandb").glob("offline-run-*")
    (log,) = offline.glob("run-*.wandb")
    records = _wandb_records(log)
    rows = [r for kind, r in records if kind == "history"]
    evals = [(row["frames"], row["eval/ttd"]) for row in rows if "eval/ttd" in row]
    assert evals == [(h["frames"], h["ttd"]) for h in result.history]
    updates = [row for row in rows if "losses/approx_kl" in row]
    assert [row["frames"] for row in updates] == [256, 512]
    assert all("losses/clip_fraction" in row for row in updates)
    (config,) = [r for kind, r in records if kind == "config"]
    assert config["algo"]["lr"] == result_cfg_lr(train_cfg)
    assert config["logger"]["mode"] == "offline"
    assert any(kind == "exit" for kind, _ in records)  # the run was finished


def _wandb_records(path: Path) -> list[tuple[str, dict[str, Any]]]:
    """A W&B run file's history rows and config as ``(kind, dict)``.

    The file is W&B's record log: a 7-byte header (``:W&B``, magic, version), then
    LevelDB log blocks of 32 KiB whose chunks (7-byte header: checksum, length, type;
    type 1 full, 2 first, 3 middle, 4 last) carry protobuf ``Record`` messages.
    """
    data = path.read_bytes()
    assert data[:4] == b":W&B"
    out: list[tuple[str, dict[str, Any]]] = []
    pos, payload = 7, b""
    while pos + 7 <= len(data):
        if 32768 - pos % 32768 < 7:  # a block's tail too short for a header: padding
            pos += 32768 - pos % 32768
            continue
        _, length, kind = struct.unpack("<IHB", data[pos : pos + 7])
        if length == 0 and kind == 0:
            break
        payload += data[pos + 7 : pos + 7 + length]
        pos += 7 + length
        if kind not in (1, 4):
            continue
        record = wandb_internal_pb2.Record()
        record.ParseFromString(payload)
        payload = b""
        which = record.WhichOneof("record_type")
        if which == "history":
            items = record.history.item
            out.append(
                (which, {i.key or "/".join(i.nested_key): json.loads(i.value_json) for i in items})
            )
        elif which == "run":
            config = {i.key: json.loads(i.value_json) for i in record.run.config.update}
            out.append(("config", config))
        else:
            out.append((which, {}))
    return out


def test_tensorboard_event_files_hold_the_metrics(train_cfg, tmp_path: Path) -> None:
    """``logger=tensorboard``: event files under ``<run>/logs`` with the evaluation TTD at
    the frames of the run's history and the PPO diagnostics at each update."""
    from tensorboard.backend.event_processing.event_accumulator import EventAccumulator

    run_dir = tmp_path / "run"
    result = train(train_cfg([*TINY, "logger=tensorboard"]), run_dir)
    (events,) = {p.parent for p in (run_dir / "logs").rglob("events.out.tfevents.*")}
    acc = EventAccumulator(str(events))
    acc.Reload()
    ttd = acc.Scalars("eval/ttd")
    assert [e.step for e in ttd] == [h["frames"] for h in result.history]
    # TensorBoard stores float32.
    assert [e.value for e in ttd] == pytest.approx([h["ttd"] for h in result.history], rel=1e-6)
    for name in ("losses/approx_kl", "losses/clip_fraction"):
        assert [e.step for e in acc.Scalars(name)] == [256, 512]
