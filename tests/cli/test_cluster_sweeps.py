"""Sweeps beyond one machine: ``rtaw-train -m`` and ``rtaw-eval -m`` on the Slurm
(submitit) and Ray launchers compose with their cluster settings. The pretrained zoo as
one sweep (``+zoo=NAME``, ``rtaw-zoo --launcher``) is tested in tests/training/test_zoo.py
and test_zoo_cli.py; a Ray-launcher sweep runs in tests/training/test_ray.py."""

from __future__ import annotations

from pathlib import Path

import pytest

from rtaw_marl.config import compose, to_typed

pytestmark = pytest.mark.system

ROOT = Path(__file__).resolve().parents[2]

#: Launcher -> (its Hydra class, settings a cluster run passes).
LAUNCHERS = {
    "joblib": ("JoblibLauncher", ["hydra.launcher.n_jobs=2"]),
    "submitit_slurm": (
        "SlurmLauncher",
        [
            "hydra.launcher.partition=cpu",
            "hydra.launcher.cpus_per_task=4",
            "hydra.launcher.timeout_min=720",
        ],
    ),
    "submitit_local": ("LocalLauncher", ["hydra.launcher.cpus_per_task=2"]),
    "ray": (
        "RayLauncher",
        ["hydra.launcher.ray.init.address=auto", "+hydra.launcher.ray.remote.num_cpus=4"],
    ),
}


@pytest.mark.parametrize("app", ["train", "eval"])
@pytest.mark.parametrize("launcher", sorted(LAUNCHERS))
def test_cluster_launchers_compose(app: str, launcher: str) -> None:
    if launcher == "ray":
        pytest.importorskip("hydra_plugins.hydra_ray_launcher")
    name, settings = LAUNCHERS[launcher]
    overrides = [f"hydra/launcher={launcher}", *settings]
    if app == "train":  # collectors as Ray actors inside each job, too
        overrides += ["collector=ray", "collector.workers=2"]
    cfg = compose(app, overrides, return_hydra_config=True)
    assert cfg.hydra.launcher._target_.rsplit(".", 1)[1] == name
    for setting in settings:
        key, _, value = setting.lstrip("+").partition("=")
        node = cfg
        for part in key.split("."):
            node = node[part]
        assert str(node) == value
    if app == "train":
        typed = to_typed(compose(app, overrides))
        assert (typed.collector.backend, typed.collector.workers) == ("ray", 2)


def test_device_cuda_without_a_gpu_is_one_line(cli, tmp_path: Path) -> None:
    """``device=cuda`` where torch sees no GPU stops before any work; ``auto`` is CPU."""
    torch = pytest.importorskip("torch")
    if torch.cuda.is_available():
        pytest.skip("this machine has a GPU")
    result = cli("train", "scenario=poc", "device=cuda", f"output_dir={tmp_path}")
    assert result.code == 2
    assert result.err.strip() == (
        "error: device=cuda but torch finds no CUDA device; use device=auto or cpu"
    )
    from rtaw_marl.training.collectors import learner_device

    assert learner_device("auto").type == "cpu"
