"""Resuming never repeats, mixes or loses anything; Ctrl-C saves and stops cleanly."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

import rtaw_marl.training.checkpoints as checkpoints_module
import rtaw_marl.training.ppo as ppo
from rtaw_marl.errors import ConfigError
from rtaw_marl.models.checkpoint import load_checkpoint, save_checkpoint
from rtaw_marl.training.checkpoints import trim_csv_logs
from rtaw_marl.training.loggers import METRICS_CSV, read_metrics
from rtaw_marl.training.ppo import train

pytestmark = pytest.mark.integration

TINY = [
    "scenario=poc", "selection.every_frames=512", "collector.envs_per_worker=4", "algo=ppo_paper",
]  # fmt: skip
RTAW_TRAIN = Path(sys.executable).with_name("rtaw-train")


def _steps(run: Path, column: str | None = None) -> list[int]:
    """The frames of the run's CSV rows (those holding ``column``)."""
    return [int(row["frames"]) for row in read_metrics(run / METRICS_CSV, column)]


def test_resume_after_a_kill_repeats_no_step(train_cfg, tmp_path: Path) -> None:
    run = tmp_path / "run"
    first = train(train_cfg([*TINY, "frames=1024"]), run)
    csv = run / METRICS_CSV
    columns = csv.read_text().splitlines()[0].split(",")
    reward = columns.index("train/reward_mean")
    # As if killed after logging two more batches but before their checkpoint, and in
    # the middle of a checkpoint write.
    with csv.open("a") as fh:
        for frames in (1536, 2048):
            cells = [str(frames)] + [""] * (len(columns) - 1)
            cells[reward] = "0.5"
            fh.write(",".join(cells) + "\n")
        fh.write("25")
    stale = run / "checkpoints" / ".last.pt.abc123.tmp"
    stale.write_bytes(b"partial")
    train(train_cfg([*TINY, "frames=2048", f"resume={first.last_checkpoint}"]), run)
    assert not stale.exists()
    steps = _steps(run)
    assert steps == sorted(set(steps))
    assert _steps(run, "train/reward_mean") == [512, 1024, 1536, 2048]
    assert 0.5 not in [row["train/reward_mean"] for row in read_metrics(csv, "train/reward_mean")]
    history = load_checkpoint(run / "checkpoints" / "last.pt")["history"]
    assert [row["frames"] for row in history] == [0, 512, 1024, 1536, 2048]


def test_trim_keeps_rows_up_to_the_checkpoint(tmp_path: Path) -> None:
    csv = tmp_path / "train" / "scalars" / "x.csv"
    csv.parent.mkdir(parents=True)
    csv.write_text("512,1.0\n1024,2.0\n1536,3.0\n")
    imitation = tmp_path / "train" / "scalars" / "imitation" / "loss.csv"
    imitation.parent.mkdir()
    imitation.write_text("90000,1.0\n")
    assert trim_csv_logs(tmp_path, 1024) == 1
    assert csv.read_text() == "512,1.0\n1024,2.0\n"
    assert imitation.read_text() == "90000,1.0\n"


def test_resume_on_another_scenario_is_refused(train_cfg, tmp_path: Path) -> None:
    first = train(train_cfg([*TINY, "frames=512"]), tmp_path / "a")
    cfg = train_cfg([*TINY, "frames=1024", "sim.num_tasks=3", f"resume={first.last_checkpoint}"])
    with pytest.raises(ConfigError, match=r"another scenario \(sim.num_tasks: 5 -> 3\)"):
        train(cfg, tmp_path / "b")


def test_resume_on_another_scenario_when_asked_resets_the_best(train_cfg, tmp_path) -> None:
    first = train(train_cfg([*TINY, "frames=512"]), tmp_path / "a")
    resumed = train(
        train_cfg(
            [*TINY, "frames=1024", "sim.num_tasks=3", "resume_new_scenario=true",
             f"resume={first.last_checkpoint}"]
        ),
        tmp_path / "b",
    )  # fmt: skip
    assert [row["frames"] for row in resumed.history] == [1024]
    best = load_checkpoint(resumed.best_checkpoint)
    assert best["best_ttd"] == resumed.history[0]["ttd"]
    assert best["config"]["sim"]["num_tasks"] == 3


def test_resume_into_a_new_folder_brings_its_best(train_cfg, tmp_path: Path) -> None:
    first = train(train_cfg([*TINY, "frames=512"]), tmp_path / "a")
    resumed = train(
        train_cfg([*TINY, "frames=1024", f"resume={first.last_checkpoint}"]), tmp_path / "b"
    )
    assert resumed.best_checkpoint.is_file()
    best = load_checkpoint(resumed.best_checkpoint)
    assert best["best_ttd"] == min(row["ttd"] for row in resumed.history)


def test_resume_needs_more_frames(train_cfg, tmp_path: Path) -> None:
    """frames= at or below the checkpoint's count is refused, not one more batch."""
    first = train(train_cfg([*TINY, "frames=1024"]), tmp_path / "a")
    cfg = train_cfg([*TINY, "frames=512", f"resume={first.last_checkpoint}"])
    with pytest.raises(ConfigError, match="already trained 1024 frames; frames=512 must be larger"):
        train(cfg, tmp_path / "b")


def test_resume_from_a_shipped_policy_is_one_clear_error(train_cfg, tmp_path: Path) -> None:
    """A shipped policy has no optimizer state: a ConfigError naming the way out, not a
    KeyError from deep inside."""
    from rtaw_marl.policies.pretrained.registry import pretrained_path

    shipped = pretrained_path("shelves_astar_m10_plus")
    cfg = train_cfg(["model=rtaw_plus", *TINY, "frames=1024", f"resume={shipped}"])
    with pytest.raises(ConfigError, match=r"no optimizer state .* resume from a run's"):
        train(cfg, tmp_path / "a")


def test_best_is_written_before_last(train_cfg, tmp_path: Path, monkeypatch) -> None:
    """A kill between the two writes must not leave a last.pt claiming a missing best."""
    written: list[str] = []
    save = checkpoints_module.save_checkpoint

    def record(path: Path, payload: dict) -> Path:
        written.append(Path(path).name)
        return save(path, payload)

    monkeypatch.setattr(checkpoints_module, "save_checkpoint", record)
    train(train_cfg([*TINY, "frames=512"]), tmp_path / "a")
    assert written[:2] == ["best.pt", "last.pt"]


def test_ctrl_c_saves_last_and_says_how_to_resume(train_cfg, tmp_path: Path, monkeypatch) -> None:
    calls = {"n": 0}
    step = ppo._train_step

    def interrupted_second_batch(*args: object, **kwargs: object) -> dict:
        calls["n"] += 1
        if calls["n"] == 2:
            os.kill(os.getpid(), signal.SIGINT)  # as a terminal's Ctrl-C
        return step(*args, **kwargs)

    monkeypatch.setattr(ppo, "_train_step", interrupted_second_batch)
    with pytest.raises(KeyboardInterrupt, match=r"saved at 1024 frames; continue with resume="):
        train(train_cfg([*TINY, "frames=4096"]), tmp_path / "a")
    ckpt = load_checkpoint(tmp_path / "a" / "checkpoints" / "last.pt")
    assert (ckpt["frames"], ckpt["iteration"]) == (1024, 2)
    # The SIGINT handler is restored.
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


@pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals")
def test_ctrl_c_with_two_workers_is_one_line_and_130(tmp_path: Path) -> None:
    """The terminal signals the whole process group: workers must stay quiet."""
    proc = subprocess.Popen(
        [str(RTAW_TRAIN), *TINY, "frames=1048576", "collector.workers=2", "progress=false",
         f"output_dir={tmp_path / 'run'}"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True,
    )  # fmt: skip
    last = tmp_path / "run" / "checkpoints" / "last.pt"
    try:
        for _ in range(600):
            if last.exists() or proc.poll() is not None:
                break
            time.sleep(0.2)
        os.killpg(proc.pid, signal.SIGINT)
        _, err = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    assert proc.returncode == 130, err
    assert "Traceback" not in err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("interrupted: ")
    assert f"continue with resume={last}" in lines[0]
    assert load_checkpoint(last)["frames"] >= 512


def test_resume_from_a_checkpoint_older_than_a_model_key(train_cfg, tmp_path: Path) -> None:
    """A run saved before ``model.critic_fleet`` existed (its ``model_config`` lacks the
    key) resumes under the key's default, and is refused under another value."""
    first = train(train_cfg([*TINY, "model=rtaw_plus", "frames=512"]), tmp_path / "a")
    ckpt = load_checkpoint(first.last_checkpoint)
    del ckpt["model_config"]["critic_fleet"]
    old = save_checkpoint(tmp_path / "old.pt", ckpt)
    resumed = train(
        train_cfg([*TINY, "model=rtaw_plus", "frames=1024", f"resume={old}"]), tmp_path / "b"
    )
    assert resumed.frames == 1024
    other = train_cfg([*TINY, "model=rtaw_plus", "model.critic_fleet=false", "frames=1024",
                       f"resume={old}"])  # fmt: skip
    with pytest.raises(ConfigError, match="differs from model"):
        train(other, tmp_path / "c")


def test_resume_from_a_run_that_says_eval_for_selection(train_cfg, tmp_path: Path) -> None:
    """A run saved before ``eval`` was renamed ``selection`` (the shipped checkpoints
    say ``eval`` too) resumes as the same scenario: its selection seeds are compared
    under today's name, and its best and history are kept."""
    first = train(train_cfg([*TINY, "frames=512"]), tmp_path / "a")
    ckpt = load_checkpoint(first.last_checkpoint)
    ckpt["config"]["eval"] = ckpt["config"].pop("selection")
    ckpt["command"] = [
        a.replace("selection.", "eval.", 1) if a.startswith("selection.") else a
        for a in ckpt["command"]
    ]
    old = save_checkpoint(tmp_path / "old.pt", ckpt)
    resumed = train(train_cfg([*TINY, "frames=1024", f"resume={old}"]), tmp_path / "b")
    assert [row["frames"] for row in resumed.history] == [0, 512, 1024]
    other = train_cfg([*TINY, "frames=1024", "selection.seeds=[1001]", f"resume={old}"])
    with pytest.raises(ConfigError, match=r"selection.seeds: \[1000, .*\] -> \[1001\]"):
        train(other, tmp_path / "c")


def test_resume_from_a_run_that_says_env_for_sim(train_cfg, tmp_path: Path) -> None:
    """A run saved before the simulator's group ``env`` was renamed ``sim`` (the shipped
    checkpoints say ``env`` too) resumes as the same scenario: its simulator keys are
    compared under today's name, and a changed one is named ``sim.*``."""
    first = train(train_cfg([*TINY, "frames=512"]), tmp_path / "a")
    ckpt = load_checkpoint(first.last_checkpoint)
    ckpt["config"] = {("env" if k == "sim" else k): v for k, v in ckpt["config"].items()}
    ckpt["command"] = [
        a.replace("sim.", "env.", 1) if a.startswith("sim.") else a for a in ckpt["command"]
    ]
    old = save_checkpoint(tmp_path / "old.pt", ckpt)
    resumed = train(train_cfg([*TINY, "frames=1024", f"resume={old}"]), tmp_path / "b")
    assert [row["frames"] for row in resumed.history] == [0, 512, 1024]
    assert "sim" in load_checkpoint(resumed.last_checkpoint)["config"]
    other = train_cfg([*TINY, "frames=1024", "sim.num_tasks=3", f"resume={old}"])
    with pytest.raises(ConfigError, match=r"another scenario \(sim.num_tasks: 5 -> 3\)"):
        train(other, tmp_path / "c")
