"""Faults a training run must survive or refuse: a kill inside a checkpoint write, a
damaged checkpoint to resume from, SIGTERM from a scheduler, budgets that would be
rounded, and budgets too long to mean."""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest
import torch

import rtaw_marl.training.evaluator as evaluator_module
from rtaw_marl.config import compose, to_typed
from rtaw_marl.errors import ConfigError
from rtaw_marl.models.checkpoint import load_checkpoint, save_checkpoint
from rtaw_marl.training.loggers import METRICS_CSV, read_metrics
from rtaw_marl.training.ppo import train
from rtaw_marl.training.progress import Estimate
from rtaw_marl.training.progress import duration as _duration

pytestmark = pytest.mark.integration

TINY = [
    "scenario=poc", "selection.every_frames=512", "collector.envs_per_worker=4", "algo=ppo_paper",
]  # fmt: skip
RTAW_TRAIN = Path(sys.executable).with_name("rtaw-train")
posix = pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals")

#: Runs rtaw-train and SIGKILLs it inside the write of the ``last.pt`` that follows a
#: new ``best.pt`` past frame 0, after part of its temporary file is written.
KILLER = """
import os, signal, sys
import rtaw_marl.training.checkpoints as checkpoints
from rtaw_marl.models import checkpoint

save, previous = checkpoints.save_checkpoint, {}

def killing_save(path, payload):
    if path.name == "last.pt" and previous.get("best.pt") == payload["frames"] > 0:
        def torn(fh):
            fh.write(b"PK\\x03\\x04 half a checkpoint")
            fh.flush()
            os.kill(os.getpid(), signal.SIGKILL)
        checkpoint.atomic_write(path, torn)
    previous[path.name] = payload["frames"]
    return save(path, payload)

checkpoints.save_checkpoint = killing_save
from rtaw_marl.cli.train import main
sys.argv = ["rtaw-train", *sys.argv[1:]]
main()
"""


def _steps(run: Path, column: str | None = None) -> list[int]:
    """The frames of the run's CSV rows (those holding ``column``)."""
    return [int(row["frames"]) for row in read_metrics(run / METRICS_CSV, column)]


@posix
def test_kill_inside_the_last_pt_write_then_resume(train_cfg, tmp_path: Path, capsys) -> None:
    """The issue's run: evaluations at 0 (TTD 22.83) and 512 frames (17.94, a new best),
    SIGKILL while last.pt's .tmp is written. The resume continues from the newer best.pt,
    evaluates no step twice and keeps the better best.pt."""
    run = tmp_path / "run"
    driver = tmp_path / "killer.py"
    driver.write_text(textwrap.dedent(KILLER))
    proc = subprocess.run(
        [sys.executable, str(driver), *TINY, "frames=2048", "progress=false",
         f"output_dir={run}"],
        capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    assert proc.returncode == -signal.SIGKILL, proc.stderr
    checkpoints = run / "checkpoints"
    assert [p.name for p in checkpoints.glob(".last.pt.*.tmp")]  # the torn write
    assert load_checkpoint(checkpoints / "last.pt")["frames"] == 0
    best_before = load_checkpoint(checkpoints / "best.pt")
    assert best_before["frames"] == 512
    assert best_before["eval"]["ttd"] < best_before["history"][0]["ttd"]

    capsys.readouterr()
    resumed = train(train_cfg([*TINY, "frames=2048", f"resume={checkpoints / 'last.pt'}"]), run)
    err = capsys.readouterr().err
    assert (
        f"resume: {checkpoints / 'best.pt'} (512 frames) is newer than {checkpoints / 'last.pt'}"
        " (0 frames, its write was interrupted): resuming from it"
    ) in err
    frames = [row["frames"] for row in resumed.history]
    assert frames == [0, 512, 1024, 1536, 2048]
    assert load_checkpoint(checkpoints / "last.pt")["history"] == resumed.history
    assert _steps(run, "eval/ttd") == frames
    steps = _steps(run)  # one row per step, in order
    assert steps == sorted(set(steps))
    best = load_checkpoint(checkpoints / "best.pt")
    ttds = [row["ttd"] for row in resumed.history]
    # Ties never replace the best: it is the first evaluation that reached the minimum.
    assert best["frames"] == frames[ttds.index(min(ttds))]
    assert best["eval"]["ttd"] == min(ttds) <= best_before["eval"]["ttd"]
    assert not list(checkpoints.glob(".*.tmp"))


@pytest.fixture(scope="module")
def base_run(tmp_path_factory) -> Path:
    """A 512-frame run's checkpoints folder (evaluations at 0 and 512 frames)."""
    run = tmp_path_factory.mktemp("base") / "run"
    train(to_typed(compose("train", ["progress=false", *TINY, "frames=512"])), run)
    return run / "checkpoints"


def test_best_on_disk_is_the_bar_a_resume_must_beat(
    train_cfg, base_run: Path, tmp_path: Path, monkeypatch
) -> None:
    """A last.pt that forgot its best (best_ttd inf) and an evaluation that only ties the
    best.pt on disk: best.pt is not replaced."""
    run = tmp_path / "run"
    (run / "checkpoints").mkdir(parents=True)
    best = (base_run / "best.pt").read_bytes()
    (run / "checkpoints" / "best.pt").write_bytes(best)
    ckpt = load_checkpoint(base_run / "last.pt")
    ckpt["best_ttd"] = float("inf")
    last = save_checkpoint(run / "checkpoints" / "last.pt", ckpt)
    tie = load_checkpoint(base_run / "best.pt")["eval"]["ttd"]
    monkeypatch.setattr(evaluator_module, "greedy_ttd", lambda net, env, seeds: [tie])
    resumed = train(train_cfg([*TINY, "frames=1024", f"resume={last}"]), run)
    assert [row["frames"] for row in resumed.history] == [0, 512, 1024]
    assert resumed.history[-1]["ttd"] == tie
    assert (run / "checkpoints" / "best.pt").read_bytes() == best


def _damage(ckpt: dict, case: str) -> None:
    if case == "iteration":
        ckpt["iteration"] = "12x"
    elif case == "frames":
        ckpt["frames"] = -512
    elif case == "best_ttd":
        ckpt["best_ttd"] = "low"
    elif case == "history":
        ckpt["history"] = "0,512"
    elif case == "history row":
        ckpt["history"] = [{"ttd": 1.0}]
    elif case == "eval":
        ckpt["eval"] = 3.5
    elif case == "optimizer state":
        del ckpt["optimizer"]["state"]
    elif case == "param groups":
        ckpt["optimizer"]["param_groups"][0]["params"] = [0]
    else:
        weight = next(iter(ckpt["model"]["actor"].values()))
        weight.fill_(float("nan"))


@pytest.mark.parametrize(
    ("case", "message"),
    [
        ("iteration", "bad.pt: iteration must be an integer >= 0, got '12x'"),
        ("frames", "bad.pt: frames must be an integer >= 0, got -512"),
        ("best_ttd", "bad.pt: best_ttd must be a number, got 'low'"),
        ("history", "bad.pt: history must be a list of evaluation rows"),
        ("history row", "bad.pt: a history row has no integer frames"),
        ("eval", "bad.pt: eval must be a dict, got float"),
        ("optimizer state", "bad.pt: its optimizer state lacks state or param_groups, so it "
                            "cannot be resumed (it can still be evaluated)"),
        ("param groups", "bad.pt does not fit this run's networks: loaded state dict "
                         "contains a parameter group that doesn't match"),
        ("nan actor", "bad.pt: model.actor.encoder.robot_embed.0.weight holds 48 "
                      "non-finite value(s) (NaN or inf)"),
    ],
)  # fmt: skip
def test_a_damaged_checkpoint_is_refused_before_any_work(
    train_cfg, base_run: Path, tmp_path: Path, case: str, message: str
) -> None:
    ckpt = load_checkpoint(base_run / "last.pt")
    _damage(ckpt, case)
    # Written as torch.save does, bypassing save_checkpoint's own additions.
    bad = tmp_path / "bad.pt"
    torch.save(ckpt, bad)
    run = tmp_path / "run"
    with pytest.raises(ConfigError) as raised:
        train(train_cfg([*TINY, "frames=1024", f"resume={bad}"]), run)
    assert message in str(raised.value)
    assert "\n" not in str(raised.value)
    assert not (run / "logs").exists()  # no evaluation, no logger: nothing ran
    assert not (run / "checkpoints").exists()


def test_a_damaged_resume_through_the_cli(cli, base_run: Path, tmp_path: Path) -> None:
    ckpt = load_checkpoint(base_run / "last.pt")
    _damage(ckpt, "iteration")
    bad = tmp_path / "bad.pt"
    torch.save(ckpt, bad)
    result = cli("train", *TINY, "frames=1024", f"resume={bad}", "progress=false",
                 f"output_dir={tmp_path / 'run'}")  # fmt: skip
    assert result.code == 2
    assert result.err == f"error: checkpoint {bad}: iteration must be an integer >= 0, got '12x'\n"


@pytest.mark.parametrize(
    ("overrides", "message"),
    [
        (["frames=1000"], "frames=1000 is not a whole number of batches of "
                          "algo.frames_per_batch = 512 (it is never rounded): use 512 or 1024"),
        (["frames=100"], "frames=100 is less than one batch (512)"),
        (["frames=1000000000000000000"], "frames=1000000000000000000 is more than 2**53 = "
                                         "9007199254740992: frame counts past it are not "
                                         "exact in the logs' steps"),
        (["frames=1024", "imitation.teacher=lookahead", "imitation.frames=1000"],
         "imitation.frames=1000 is not a whole number of imitation.rounds x "
         "collector.envs_per_worker = 16 (it is never rounded): use 992 or 1008"),
        (["frames=1024", "selection.seeds=[1000,1001,1000]"],
         "selection.seeds lists a seed more than once: 1000 (2 times); each seed is one "
         "episode, list it once"),
    ],
)  # fmt: skip
def test_budgets_are_never_rounded(cli, tmp_path: Path, overrides: list, message: str) -> None:
    result = cli("train", *TINY, *overrides, "progress=false", f"output_dir={tmp_path / 'r'}")
    assert result.code == 2
    assert result.err == f"error: {message}\n"
    assert not (tmp_path / "r").exists()


def test_a_resume_budget_counts_whole_batches_from_its_checkpoint(
    train_cfg, base_run: Path, tmp_path: Path
) -> None:
    """512 frames done, batches now of 384: frames=1536 would leave 1024, not whole."""
    cfg = train_cfg([*TINY, "algo.frames_per_batch=384", "frames=1536",
                     f"resume={base_run / 'last.pt'}"])  # fmt: skip
    with pytest.raises(ConfigError) as raised:
        train(cfg, tmp_path / "run")
    assert str(raised.value) == (
        "resume: frames=1536 leaves 1024 frames after the checkpoint's 512, not a whole "
        "number of batches of algo.frames_per_batch=384: use frames=1280 or 1664"
    )


def test_the_estimate_is_printed_once_for_a_long_run(train_cfg, capsys) -> None:
    """Training at 256 frames/s and 2 s an evaluation: 1,048,064 frames and 2,047
    evaluations left are 4,094 + 4,094 s; printed after the third batch, once."""
    estimate = Estimate(train_cfg([*TINY, "frames=1048576"]), 0)
    totals = {"time/collect_s": 1.0, "time/update_s": 1.0, "time/eval_checkpoint_s": 9.0}
    assert estimate.report(512, totals, [2.0]) == "2h16m"
    assert estimate.report(512, totals, [2.0]) == "2h16m"
    assert capsys.readouterr().out == ""
    estimate.report(512, totals, [2.0])
    estimate.report(512, totals, [2.0])
    assert capsys.readouterr().out == (
        "estimated time left: 2h16m (1048064 frames at 256 frames/s, evaluations included)\n"
    )


def test_a_short_run_prints_no_estimate(train_cfg, capsys) -> None:
    estimate = Estimate(train_cfg([*TINY, "frames=2048"]), 0)
    for _ in range(4):
        estimate.report(512, {"time/collect_s": 0.5}, [1.0])
    assert capsys.readouterr() == ("", "")


def test_an_absurd_budget_warns_after_the_first_batch(train_cfg, capsys) -> None:
    estimate = Estimate(train_cfg([*TINY, f"frames={2**53}"]), 0)
    estimate.report(512, {"time/collect_s": 2.0}, [])
    out, err = capsys.readouterr()
    assert out == ""
    assert err == (
        f"warning: frames={2**53} would take about 1.11e+06 years at the measured 256 "
        "frames/s; Ctrl-C or SIGTERM saves and stops\n"
    )


@pytest.mark.parametrize(
    ("seconds", "text"),
    [(42.4, "42s"), (725, "12m05s"), (11_220, "3h07m"), (4.2 * 86400, "4.2 days"),
     (3.1e4 * 365.25 * 86400, "3.1e+04 years")],
)  # fmt: skip
def test_durations(seconds: float, text: str) -> None:
    assert _duration(seconds) == text


@posix
def test_sigterm_saves_says_one_line_and_exits_143(train_cfg, tmp_path: Path) -> None:
    """A scheduler signals the whole process group: the two collector workers ignore it,
    the main process saves last.pt, prints one line and exits 128 + 15; no leaked
    semaphores. The run then resumes from that last.pt."""
    last = tmp_path / "run" / "checkpoints" / "last.pt"
    proc = subprocess.Popen(
        [str(RTAW_TRAIN), *TINY, "frames=1048576", "collector.workers=2", "progress=false",
         f"output_dir={tmp_path / 'run'}"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True,
    )  # fmt: skip
    try:
        for _ in range(600):
            if last.exists() or proc.poll() is not None:
                break
            time.sleep(0.2)
        os.killpg(proc.pid, signal.SIGTERM)
        _, err = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    assert proc.returncode == 143, err
    assert "Traceback" not in err
    assert "leaked semaphore" not in err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert re.fullmatch(
        rf"interrupted: {re.escape(str(last))} saved at (\d+) frames; "
        rf"continue with resume={re.escape(str(last))}",
        lines[0],
    ), lines[0]
    frames = load_checkpoint(last)["frames"]
    assert frames >= 512
    assert f"saved at {frames} frames" in lines[0]
    resumed = train(
        train_cfg([*TINY, f"frames={frames + 512}", f"resume={last}"]), tmp_path / "run"
    )
    assert resumed.frames == frames + 512
    assert resumed.history[-1]["frames"] == frames + 512
