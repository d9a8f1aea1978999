"""``rtaw-zoo``: one-line errors, the commands it prints, what it trains and ships."""

from __future__ import annotations

import shlex
import shutil
import subprocess
from pathlib import Path

import pytest
from omegaconf import OmegaConf

from rtaw_marl.config import compose
from rtaw_marl.models.checkpoint import load_checkpoint
from rtaw_marl.policies.pretrained.registry import pretrained_path
from rtaw_marl.training import retrain
from rtaw_marl.training.zoo import ZOO, train_command

pytestmark = pytest.mark.integration


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["nope"], "error: unknown zoo entry 'nope'; available: A_astar_m10"),
        (["A_astar_m10_long"], "error: A_astar_m10_long continues A_astar_m10, but "),
        (["C256_astar_m500_random_plus"], "rtaw-zoo C256_astar_m100_random_plus"),
        (["--jobs", "two"], "error: argument --jobs: invalid int value: 'two'"),
        (["--launcher", "moon"], "error: argument --launcher: invalid choice"),
    ],
)
def test_bad_input_is_one_error_line_and_status_2(cli, args: list[str], message: str) -> None:
    result = cli("zoo", *args)
    assert result.code == 2
    assert len(result.err.strip().splitlines()) == 1
    assert message in result.err
    assert not Path("runs").exists()  # nothing started


def test_print_shows_each_entrys_command(cli) -> None:
    result = cli("zoo", "--print", "A_astar_m10", "A_astar_m10_long")
    lines = result.out.strip().splitlines()
    assert result.code == 0
    runs = Path("runs/pretrained")
    assert [shlex.split(line) for line in lines] == [
        train_command(n, runs / n) for n in ("A_astar_m10", "A_astar_m10_long")
    ]


def test_the_zoo_sweep_names_one_folder_per_entry(cli, tmp_path: Path) -> None:
    """``--launcher ray --print``: one rtaw-train -m command, each job in
    ``runs/pretrained/sweep/<name>``; staged entries are left out with a note."""
    result = cli("zoo", "--launcher", "ray", "--print", "--set",
                 "hydra.launcher.ray.init.address=auto", "A_astar_m10", "B_astar_m10_plus",
                 "B_astar_m10_long")  # fmt: skip
    assert result.code == 0
    assert "left out of the sweep" in result.err
    assert "B_astar_m10_long" in result.err
    args = shlex.split(result.out)
    assert args[0].endswith("rtaw-train")
    assert args[1:4] == ["--multirun", "+zoo=A_astar_m10,B_astar_m10_plus", "hydra/launcher=ray"]
    assert "hydra.launcher.ray.init.address=auto" in args
    job = [a for a in args[2:] if not a.startswith("+zoo=")]
    cfg = compose("train", ["+zoo=B_astar_m10_plus", *job], return_hydra_config=True)
    assert cfg.hydra.sweep.dir == str(tmp_path / "runs" / "pretrained" / "sweep")
    # Each job's folder is its entry's name: the subdir names the zoo choice.
    assert OmegaConf.to_container(cfg.hydra.sweep)["subdir"] == "${hydra:runtime.choices.zoo}"
    assert cfg.hydra.runtime.choices.zoo == "B_astar_m10_plus"
    assert cfg.model.name == "rtaw_plus"


def test_summary_lists_the_shipped_policies(cli, tmp_path: Path) -> None:
    shipped = tmp_path / "shipped"
    shipped.mkdir()
    shutil.copy(pretrained_path("C_astar_m10_long"), shipped)
    result = cli("zoo", "--summary", "--ship-to", str(shipped))
    assert result.code == 0
    lines = result.out.strip().splitlines()
    assert len(lines) == 3
    assert lines[2].startswith("| C_astar_m10_long | rtaw | ")
    assert " / 1,228,800 |" in lines[2]


def test_a_continued_entry_copies_its_base_run_resumes_it_and_ships(monkeypatch, tmp_path):
    """The staged entry runs after its base's run exists; the copy of that run folder is
    resumed, and the best checkpoint is shipped with the command that trained it."""
    runs, shipped, curves = tmp_path / "runs", tmp_path / "shipped", tmp_path / "img"
    base = runs / "A_astar_m10"
    (base / "checkpoints").mkdir(parents=True)
    shutil.copy(pretrained_path("A_astar_m10"), base / "checkpoints" / "best.pt")
    (base / "training_curve.png").write_bytes(b"png")
    commands = []

    def fake_run(cmd, check, stdout, stderr):
        commands.append(cmd)
        assert (runs / "A_astar_m10_long" / "checkpoints" / "best.pt").is_file()  # the copy
        return subprocess.CompletedProcess(cmd, 0)

    monkeypatch.setattr(retrain.subprocess, "run", fake_run)
    lines = retrain.train_entries(["A_astar_m10_long"], 1, runs, shipped, curves)
    assert commands == [train_command("A_astar_m10_long", runs / "A_astar_m10_long", runs)]
    assert lines[0].startswith("A_astar_m10_long: best selection TTD")
    ckpt = load_checkpoint(shipped / "A_astar_m10_long.pt")
    assert ckpt["command"] == commands[0]
    assert "optimizer" not in ckpt
    assert (curves / "training_A_astar_m10_long.png").read_bytes() == b"png"


def test_select_and_phases() -> None:
    plus = retrain.select([], plus=True)
    assert plus
    assert all(ZOO[n].model == "rtaw_plus" for n in plus)
    paper = retrain.select([], paper=True)
    assert set(plus) | set(paper) == set(ZOO)
    assert not set(plus) & set(paper)
    first, later = retrain.phases(
        ["A_astar_m10_long", "A_astar_m10", "C256_astar_m500_random_plus"]
    )
    assert (first, later) == (["A_astar_m10"], ["A_astar_m10_long", "C256_astar_m500_random_plus"])


def test_rtaw_zoo_without_the_training_extra_fails_with_one_line(monkeypatch, capsys) -> None:
    import sys

    import rtaw_marl.cli

    monkeypatch.setitem(sys.modules, "torch", None)
    monkeypatch.setattr(sys, "argv", ["rtaw-zoo", "A_astar_m10"])
    with pytest.raises(SystemExit) as exc:
        rtaw_marl.cli.zoo_main()
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert (
        err == "error: rtaw-zoo needs the training extra ('torch' is not installed): "
        "pip install 'rtaw_marl[train]'\n"
    )
