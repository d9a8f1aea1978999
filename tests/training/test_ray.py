"""``rtaw-train collector=ray`` (collectors as Ray actors) and sweeps on Hydra's Ray
launcher, on a local Ray cluster.

The settings checks run first, without Ray up. One local cluster then serves the rest of
the module (Ray takes seconds to start): the training runs join it as they would join a
Ray job's cluster (``collector.ray.address`` is then not used), and it stops when the
module ends. Skipped when Ray is not installed (the ``ray`` extra; ``make test``
installs it).
"""

from __future__ import annotations

import json
import socket
import time
from pathlib import Path

import pytest
import torch

from rtaw_marl.models.checkpoint import load_checkpoint
from rtaw_marl.training.loggers import METRICS_CSV, read_metrics
from rtaw_marl.training.ppo import train
from tests.training.conftest import compose_train

pytestmark = pytest.mark.system

ray = pytest.importorskip("ray")

#: Two actors of 4 simulators each; the paper's 512-frame batches (64 steps per actor).
SMALL = [
    "scenario=poc", "collector=ray", "collector.workers=2", "collector.envs_per_worker=4",
    "algo=ppo_paper", "selection.seeds=[1000,1001]", "selection.every_frames=512", "progress=false",
]  # fmt: skip


def _closed_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.mark.parametrize(
    ("override", "message"),
    [
        ("collector.workers=0", "collector.workers must be >= 1, got 0"),
        ("collector.ray.cpus_per_actor=0", "collector.ray.cpus_per_actor must be > 0, got 0"),
        ("collector.ray.cpus_per_actor=-1", "collector.ray.cpus_per_actor must be > 0, got -1"),
        ("collector.ray.address=nohost", "must be local, auto, HOST:PORT or ray://HOST:PORT"),
        ("collector.ray.address=127.0.0.1:{closed}", "no Ray head answers there"),
        # A non-routable address: no answer within connect_timeout_s (1 s here), or, on
        # a network whose proxy answers every address, no Ray head behind the answer.
        ("collector.ray.address=10.255.255.1:6379", "collector.ray.address=10.255.255.1:6379"),
    ],
)
def test_bad_ray_settings_are_one_line_exit_2(cli, tmp_path: Path, override: str, message: str):
    if ray.is_initialized():
        pytest.skip("Ray is up in this process: the address would not be used")
    start = time.monotonic()
    override = override.format(closed=_closed_port())
    result = cli("train", *SMALL, "frames=512", "collector.ray.connect_timeout_s=1",
                 override, f"output_dir={tmp_path / 'run'}")  # fmt: skip
    assert result.code == 2
    lines = result.err.strip().splitlines()
    assert len(lines) == 1, result.err
    assert lines[0].startswith("error: ")
    assert message in lines[0]
    assert not ray.is_initialized()
    assert time.monotonic() - start < 15  # Ray alone retries for 20 s or more


@pytest.fixture(scope="module")
def ray_cluster():
    """A local Ray cluster for the module (4 logical CPUs on whatever cores there are)."""
    ray.init(address="local", num_cpus=4, include_dashboard=False, logging_level="error")
    yield
    ray.shutdown()


def _steps(run_dir: Path) -> list[int]:
    """Frames at each logged iteration (the CSV logger's steps)."""
    return [int(row["frames"]) for row in read_metrics(run_dir / METRICS_CSV, "charts/fps")]


def test_two_actors_train_like_two_local_workers_and_resume(cli, ray_cluster, tmp_path: Path):
    """Two Ray actors: every batch exactly algo.frames_per_batch, the same networks as
    two local worker processes (exact weight sync), a checkpoint that rtaw-eval
    evaluates, and resume through the Ray backend."""
    run = tmp_path / "ray"
    result = cli("train", *SMALL, "frames=1024", f"output_dir={run}")
    assert result.code == 0, result.err
    last = run / "checkpoints" / "last.pt"
    ckpt = load_checkpoint(last)
    assert (ckpt["frames"], ckpt["iteration"]) == (1024, 2)
    assert ckpt["config"]["collector"]["backend"] == "ray"
    assert _steps(run) == [512, 1024]
    # Two local worker processes, same seeds: the same batches, so the same networks.
    local = train(compose_train([*SMALL, "frames=1024", "collector=local"]), tmp_path / "local")
    same = load_checkpoint(local.last_checkpoint)["model"]
    for net in ("actor", "critic"):
        assert all(torch.equal(ckpt["model"][net][k], v) for k, v in same[net].items())
    # rtaw-eval reads the checkpoint.
    out = tmp_path / "results.json"
    result = cli("eval", "scenario=poc", "policy=checkpoint", f"checkpoint={last}",
                 "seeds=[0]", f"output={out}")  # fmt: skip
    assert result.code == 0, result.err
    assert len(json.loads(out.read_text())["policies"]) == 1
    # Resume through the Ray backend into a new folder: 1024 -> 2048 frames.
    more = tmp_path / "more"
    result = cli("train", *SMALL, "frames=2048", f"resume={last}", f"output_dir={more}")
    assert result.code == 0, result.err
    after = load_checkpoint(more / "checkpoints" / "last.pt")
    assert (after["frames"], after["iteration"]) == (2048, 4)
    assert [row["frames"] for row in after["history"]] == [0, 512, 1024, 1536, 2048]
    assert _steps(more) == [1536, 2048]


def test_more_cpus_than_the_cluster_has_is_one_line(cli, ray_cluster, tmp_path: Path):
    result = cli("train", *SMALL, "frames=512", "collector.ray.cpus_per_actor=3",
                 "collector.ray.connect_timeout_s=1", f"output_dir={tmp_path}")  # fmt: skip
    assert result.code == 2
    assert result.err.strip() == (
        "error: collector.workers=2 Ray actors x collector.ray.cpus_per_actor=3 need 6 "
        "CPUs; the Ray cluster has 4 free of 4"
    )


@pytest.mark.slow
def test_poc_reaches_the_exhaustive_optimum_through_ray(train_cfg, ray_cluster, tmp_path):
    """The local PoC test's settings (tests/training/test_learning.py), two Ray actors."""
    cfg = train_cfg(["scenario=poc", "frames=6144", "selection.every_frames=1024", "seed=0",
                     "collector=ray", "collector.workers=2"])  # fmt: skip
    result = train(cfg, tmp_path)
    assert result.frames == 6144
    assert result.mpdm_ttd == pytest.approx(22.737, abs=1e-3)
    assert result.best_ttd == pytest.approx(17.936, abs=1e-3)


def test_eval_sweep_on_the_ray_launcher(cli, ray_cluster, tmp_path: Path):
    """``rtaw-eval -m ... hydra/launcher=ray``: each job runs as a Ray task."""
    pytest.importorskip("hydra_plugins.hydra_ray_launcher")
    sweep = tmp_path / "sweep"
    result = cli("eval", "--multirun", "scenario=poc", "seeds=[0]", "policy=[mpdm]",
                 "sim.num_tasks=4,5", "hydra/launcher=ray", f"hydra.sweep.dir={sweep}")  # fmt: skip
    assert result.code == 0, result.err
    done = {p.parent.name: json.loads(p.read_text()) for p in sweep.glob("*/results.json")}
    assert sorted(done) == ["0", "1"]
    # The full 5-task proof of concept: MPDM's exact total.
    assert done["1"]["policies"]["mpdm"]["ttd"] == [pytest.approx(22.737, abs=1e-3)]
