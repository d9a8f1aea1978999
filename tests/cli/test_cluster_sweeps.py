"""Sweeps beyond one machine: ``rtaw-train -m`` and ``rtaw-eval -m`` on the Slurm
(submitit) and Ray launchers compose with their cluster settings, and the pretrained zoo
is one sweep (``+zoo=NAME``). A Ray-launcher sweep runs in tests/training/test_ray.py."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
from omegaconf import OmegaConf

from rtaw_marl.config import as_plain, compose, to_typed
from rtaw_marl.errors import ConfigError
from rtaw_marl.policies.pretrained.registry import CONTINUED, PRETRAINED

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


def test_every_zoo_entry_is_its_registry_recipe() -> None:
    """``+zoo=NAME`` composes exactly the overrides the registry lists for ``NAME``;
    continued entries are no zoo option (they resume a copy of their base's folder)."""
    for name in CONTINUED:
        with pytest.raises(ConfigError, match=name):
            compose("train", [f"+zoo={name}"])
    for name, overrides in PRETRAINED.items():
        if name in CONTINUED:
            continue
        assert as_plain(to_typed(compose("train", [f"+zoo={name}"]))) == as_plain(
            to_typed(compose("train", overrides))
        ), name


def test_zoo_sweep_command_names_one_folder_per_entry() -> None:
    """``train_pretrained.py --launcher ray --print``: one rtaw-train -m command, each
    job in ``runs/pretrained/sweep/<name>``."""
    proc = subprocess.run(
        [sys.executable, "experiments/train_pretrained.py", "--launcher", "ray", "--print",
         "--set", "hydra.launcher.ray.init.address=auto", "A_astar_m10", "B_astar_m10_plus"],
        cwd=ROOT, capture_output=True, text=True, check=True,
    )  # fmt: skip
    args = proc.stdout.split()
    assert args[0].endswith("rtaw-train")
    assert args[1:4] == ["--multirun", "+zoo=A_astar_m10,B_astar_m10_plus", "hydra/launcher=ray"]
    assert "hydra.launcher.ray.init.address=auto" in args
    job = [a.strip("'") for a in args[2:] if a != "+zoo=A_astar_m10,B_astar_m10_plus"]
    cfg = compose("train", ["+zoo=B_astar_m10_plus", *job], return_hydra_config=True)
    assert cfg.hydra.sweep.dir == str(ROOT / "runs" / "pretrained" / "sweep")
    # Each job's folder is its entry's name: the subdir names the zoo choice.
    assert OmegaConf.to_container(cfg.hydra.sweep)["subdir"] == "${hydra:runtime.choices.zoo}"
    assert cfg.hydra.runtime.choices.zoo == "B_astar_m10_plus"
    assert cfg.model.name == "rtaw_plus"


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
