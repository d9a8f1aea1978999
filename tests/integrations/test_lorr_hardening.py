"""rtaw-lorr keeps what it ran and refuses before any run what it cannot run.

The refusals need no start kit (they come before it is built); the stopped and resumed
two-scheduler run and the build under a cache path with a space need the kit.
"""

from __future__ import annotations

import fcntl
import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from rtaw_marl.integrations.lorr.kit import set_track
from rtaw_marl.sim.maps import map_path
from rtaw_marl.utils.runs import lock_name

PROBLEM = map_path("random_32_32_20_100.json")
KIT = Path(__file__).resolve().parents[2].parent / "shared" / "lorr" / "start-kit-v2.1.2"
needs_kit = pytest.mark.skipif(not KIT.is_dir(), reason=f"no LoRR start kit at {KIT}")


def lorr(*args: str, cwd: Path | None = None) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "rtaw_marl.cli.lorr", *args],
        capture_output=True, text=True, cwd=cwd, timeout=600,
    )  # fmt: skip


def one_line_error(done: subprocess.CompletedProcess[str], message: str) -> None:
    assert done.returncode == 2, done.stderr
    assert message in done.stderr, done.stderr
    assert "Traceback" not in done.stderr
    assert len(done.stderr.strip().splitlines()) == 1, done.stderr


@pytest.mark.integration
@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["policy=[mpdm,mpdm]"], "two policies are labelled 'mpdm'"),
        (["policy=pretrained", "pretrained=[generalist,generalist]"], "names 'generalist' twice"),
        (["timesteps=99999999999"], "timesteps must be <= 2147483647"),
        (["plan_time_ms=10000000000000"], "plan_time_ms must be <= 2147483647"),
        (["policy=checkpoint", "checkpoint=/etc/hostname"], "/etc/hostname"),
        (["overflow=later"], "unknown overflow 'later'; available: nearest, wait"),
    ],
)
def test_bad_runs_are_refused_before_any_run(tmp_path: Path, args: list[str], message: str) -> None:
    done = lorr(f"problem={PROBLEM}", *args, f"hydra.run.dir={tmp_path / 'run'}")
    one_line_error(done, message)
    assert not (tmp_path / "run" / "results.json").exists()


@pytest.mark.integration
def test_a_damaged_problem_is_refused_as_rtaw_eval_refuses_it(tmp_path: Path) -> None:
    """The one reader: an agent file whose robots share a start, refused by both."""
    folder = tmp_path / "p"
    shutil.copytree(PROBLEM.parent, folder)
    agents = (folder / "agents" / "random_32_32_20_100.agents").read_text().splitlines()
    agents[3] = agents[2]
    (folder / "agents" / "random_32_32_20_100.agents").write_text("\n".join(agents) + "\n")
    problem = folder / PROBLEM.name
    message = "robots 0 and 1 start on the same location"
    one_line_error(lorr(f"problem={problem}", f"hydra.run.dir={tmp_path / 'r'}"), message)
    done = subprocess.run(
        [sys.executable, "-m", "rtaw_marl.cli.eval", "scenario=lorr", f"tasks.problem={problem}",
         "sim.horizon=20", "policy=mpdm", "seeds=[0]", f"hydra.run.dir={tmp_path / 'e'}"],
        capture_output=True, text=True,
    )  # fmt: skip
    assert done.returncode == 2
    assert message in done.stderr


@pytest.mark.integration
def test_a_held_output_is_refused(tmp_path: Path) -> None:
    """Two runs writing one results.json: the second stops at once, naming it."""
    output = tmp_path / "same.json"
    with open(tmp_path / lock_name(output.name), "w") as held:
        fcntl.flock(held.fileno(), fcntl.LOCK_EX)
        held.write(f"{os.getpid()}\n")
        held.flush()
        done = lorr(f"problem={PROBLEM}", f"output={output}", f"hydra.run.dir={tmp_path / 'r'}")
    assert done.returncode == 2, done.stderr
    assert "same.json" in done.stderr
    assert "Traceback" not in done.stderr
    assert not output.exists()


@pytest.mark.integration
def test_set_track_under_a_path_with_a_space_touches_nothing_else(tmp_path: Path) -> None:
    """The kit's set_track.bash ran rm -rf on its unquoted folder: under "victim x" it
    emptied "victim". The Python version fills python/tmp and nothing else."""
    if not KIT.is_dir():
        pytest.skip(f"no LoRR start kit at {KIT}")
    victim = tmp_path / "victim"
    (victim / "tmp").mkdir(parents=True)
    (victim / "tmp" / "keep.txt").write_text("keep")
    root = tmp_path / "victim x"
    shutil.copytree(KIT / "python", root / "python")
    set_track(root, "scheduler")
    assert (victim / "tmp" / "keep.txt").read_text() == "keep"
    made = sorted(p.name for p in (root / "python" / "tmp").iterdir())
    expected = sorted(
        p.name
        for name in ("common", "default_planner", "user_scheduler")
        for p in (KIT / "python" / name).iterdir()
    )
    assert made == expected


def _wait_for_run(output: Path, label: str, proc: subprocess.Popen[str]) -> None:
    deadline = time.monotonic() + 300
    while time.monotonic() < deadline and proc.poll() is None:
        if output.exists() and label in json.loads(output.read_text()).get("runs", {}):
            return
        time.sleep(0.2)
    proc.kill()
    raise AssertionError(f"{label} never reached {output}: {proc.communicate()}")


@pytest.mark.system
@needs_kit
def test_a_stopped_two_scheduler_run_keeps_the_first_and_resumes(tmp_path: Path) -> None:
    """SIGTERM while rbts runs: mpdm's counts stay in results.json, one line says how to
    go on, and resume=true runs rbts only, into the same run folder."""
    output, run = tmp_path / "r.json", tmp_path / "run"
    args = [sys.executable, "-m", "rtaw_marl.cli.lorr", f"problem={PROBLEM}",
            "policy=[mpdm,rbts]", "timesteps=300", "plan_time_ms=40", f"output={output}",
            f"hydra.run.dir={run}"]  # fmt: skip
    proc = subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    _wait_for_run(output, "mpdm", proc)
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 143, err
    assert "stopped: mpdm kept in" in err
    assert "resume=true to run rbts" in err
    kept = json.loads(output.read_text())
    assert set(kept["runs"]) == {"mpdm"}
    assert kept["pending"] == ["rbts"]
    assert kept["runs"]["mpdm"]["tasks_finished"] > 0

    again = lorr(*args[3:])
    one_line_error(again, "already holds a run of mpdm")

    done = lorr(*args[3:], "resume=true")
    assert done.returncode == 0, done.stderr
    assert "resume: mpdm kept from" in done.stdout
    assert "mpdm: lifelong" not in done.stdout
    assert "rbts: lifelong" in done.stdout
    final = json.loads(output.read_text())
    assert set(final["runs"]) == {"mpdm", "rbts"}
    assert final["pending"] == []
    assert final["runs"]["mpdm"] == kept["runs"]["mpdm"]
    assert final["runs"]["rbts"]["schedule_errors"] == 0

    changed = lorr(*args[3:-1], f"hydra.run.dir={tmp_path / 'other'}", "resume=true",
                   "timesteps=299")  # fmt: skip
    one_line_error(changed, "was run with timesteps=300")


@pytest.mark.integration
def test_a_build_under_a_cache_path_with_a_space_runs_no_shell(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """build_kit into RTAW_LORR_CACHE="<tmp>/victim x" (the compiler replaced by a
    recorder): "<tmp>/victim" survives and no step is a shell script. A real build
    there was checked by hand (docs/lorr.md)."""
    if not KIT.is_dir():
        pytest.skip(f"no LoRR start kit at {KIT}")
    from rtaw_marl.integrations.lorr import kit as kit_module

    victim = tmp_path / "victim"
    (victim / "tmp").mkdir(parents=True)
    (victim / "tmp" / "keep.txt").write_text("keep")
    commands: list[list[str]] = []

    def record(command: list[str], **_: object) -> subprocess.CompletedProcess[str]:
        commands.append(list(command))
        return subprocess.CompletedProcess(command, 0)

    monkeypatch.setattr(kit_module.subprocess, "run", record)
    monkeypatch.setattr(kit_module, "check_system_packages", lambda: None)
    monkeypatch.setenv("RTAW_LORR_CACHE", str(tmp_path / "victim x"))
    build = kit_module.build_kit("python", log=lambda line: None)
    assert (victim / "tmp" / "keep.txt").read_text() == "keep"
    assert [c[0] for c in commands] == ["cmake", "make"]
    assert (build.root / "python" / "tmp" / "pyTaskScheduler.cpp").is_file()
