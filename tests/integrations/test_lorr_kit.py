"""rtaw_marl policies as the task scheduler of LoRR's own simulator (its 2024 start kit).

The kit is built once per machine (``make test`` builds it first; otherwise the first
test here does, a few minutes) into ``~/.cache/rtaw_marl/lorr``. Runs use the start
kit's random 32x32 problem with 100 robots for 200 timesteps at 50 ms per timestep.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from rtaw_marl.errors import ConfigError
from rtaw_marl.integrations.lorr import kit as kit_module
from rtaw_marl.integrations.lorr.entry import RunSpec
from rtaw_marl.integrations.lorr.kit import KitBuild, StartKitError, build_kit, kit_source
from rtaw_marl.integrations.lorr.output import read_replay, replay
from rtaw_marl.integrations.lorr.run import LoRRRun, run_lifelong
from rtaw_marl.sim.lorr import read_problem

pytestmark = pytest.mark.system

KIT = Path(__file__).resolve().parents[2].parent / "shared" / "lorr" / "start-kit-v2.1.2"
RANDOM = KIT / "example_problems" / "random.domain" / "random_32_32_20_100.json"
STEPS, PLAN_MS = 200, 50

needs_kit = pytest.mark.skipif(not RANDOM.is_file(), reason=f"no LoRR start kit at {KIT}")


@pytest.fixture(scope="module")
def build() -> KitBuild:
    if not RANDOM.is_file():
        pytest.skip(f"no LoRR start kit at {KIT}")
    return build_kit("python")


def _spec(policy: str, **keys: object) -> RunSpec:
    return RunSpec(problem=str(RANDOM), policy=policy, stats="stats.json", timesteps=STEPS, **keys)


@pytest.fixture(scope="module")
def official(build: KitBuild, tmp_path_factory: pytest.TempPathFactory) -> dict[str, LoRRRun]:
    """MPDM and the shipped generalist RTAW+, each one lifelong run."""
    pytest.importorskip("torch")
    root = tmp_path_factory.mktemp("lorr")
    specs = {"mpdm": _spec("mpdm"), "generalist": _spec("pretrained", source="generalist_plus")}
    # The network decides more slowly than MPDM: with 50 ms on a loaded CI machine it
    # deferred most robots of the first timesteps (131 tasks once); twice the time keeps
    # the test about the scheduler, not the machine's load.
    plan_ms = {"mpdm": PLAN_MS, "generalist": 2 * PLAN_MS}
    return {
        name: run_lifelong(build, RANDOM, root / name, spec, name, STEPS, plan_ms[name])
        for name, spec in specs.items()
    }


@needs_kit
@pytest.mark.parametrize("name", ["mpdm", "generalist"])
def test_official_simulator_runs_our_schedulers(official: dict[str, LoRRRun], name: str) -> None:
    """No schedule errors, no invalid moves; every assignment was the policy's decision;
    the output replays (turns, moves, events at their errands) to its own count."""
    run = official[name]
    assert run.schedule_errors == 0
    assert run.planner_errors == 0
    assert run.timesteps == STEPS
    assert run.team_size == 100
    assert run.tasks_finished > 200  # LoRR's default entry finishes ~2 per timestep here
    assert run.scheduler["decisions"] >= run.tasks_finished
    assert run.scheduler["errors"] == []
    again = read_replay(run.output, read_problem(RANDOM).layout())
    assert again.tasks_finished == run.tasks_finished


@needs_kit
def test_lifelong_output_opens_in_the_viewer(official: dict[str, LoRRRun]) -> None:
    """LoRR's own output (turning action model) as a schedule for rtaw-view: its tasks
    finished are the run's, every robot's cells are the replay's, the page builds."""
    from rtaw_marl.integrations.lorr.output import read_schedule
    from rtaw_marl.viz.view import ViewEpisode, page

    run, layout = official["mpdm"], read_problem(RANDOM).layout()
    schedule = read_schedule(run.output, layout)
    assert int((schedule.task_delivered <= schedule.horizon).sum()) == run.tasks_finished
    played = read_replay(run.output, layout)
    assert np.array_equal(schedule.positions, played.positions[..., ::-1])
    assert (schedule.task_pickup <= schedule.task_delivered).all()
    assert "rtaw-data" in page(layout, [ViewEpisode("lifelong", schedule)], "LoRR")


@needs_kit
def test_own_simulator_predicts_the_official_count(official: dict[str, LoRRRun]) -> None:
    """The project's PIBT simulator, same problem, MPDM, 200 timesteps: with LoRR's
    action model and guidance (the defaults) its count is within 10% of LoRR's; the
    turn-free model without guidance finishes far more (its robots turn in no time)."""
    from rtaw_marl.evaluation.evaluate import run_episode
    from rtaw_marl.policies import make_baseline
    from rtaw_marl.scenarios.lorr import lorr_scenario
    from rtaw_marl.sim.builder import build_sim

    def own(navigator: dict) -> int:
        sim = build_sim(lorr_scenario(RANDOM, horizon=STEPS, navigator=navigator).spec())
        return run_episode(sim, make_baseline("mpdm"), 0).tasks_finished

    lorr = official["mpdm"].tasks_finished
    assert abs(own({"name": "pibt"}) - lorr) <= 0.1 * lorr
    assert own({"name": "pibt", "turns": False, "guidance": 0.0}) > 1.25 * lorr


@needs_kit
def test_pair_greedy_reassigns_inside_lifelong(build: KitBuild, tmp_path: Path) -> None:
    """The winner's scheduler in LoRR's simulator: LoRR accepts every schedule, including
    the ones that move tasks not started to other robots."""
    run = run_lifelong(
        build, RANDOM, tmp_path / "pg", _spec("pair_greedy"), "pair_greedy", STEPS, PLAN_MS
    )
    assert run.schedule_errors == 0
    assert run.planner_errors == 0
    assert run.scheduler["reassigned"] > 0
    assert run.tasks_finished > 200


@needs_kit
def test_own_executor_plans_inside_lifelong(tmp_path: Path) -> None:
    """The own PIBT executor as LoRR's planner (planner track, the kit's scheduler): no
    invalid moves, and LoRR's robots end every timestep where the executor predicted
    (the two action models agree: no mismatch)."""
    from rtaw_marl.integrations.lorr.planner import PlannerSpec

    spec = PlannerSpec(
        problem=str(RANDOM),
        stats="stats.json",
        timesteps=STEPS,
        patience=16,
        guidance=1.0,
        guide_replans=0,
    )
    run = run_lifelong(build_kit("planner"), RANDOM, tmp_path / "p", spec, "pibt", STEPS, PLAN_MS)
    assert run.planner_errors == 0
    assert run.schedule_errors == 0
    assert run.scheduler["errors"] == []
    assert run.scheduler["mismatches"] == 0
    assert run.scheduler["timesteps"] == STEPS
    assert run.tasks_finished > 200


@needs_kit
def test_own_episode_round_trips_through_lorr_format(tmp_path: Path) -> None:
    """An own PIBT episode written in LoRR's format replays to the same cells at every
    timestep and the same tasks finished."""
    from rtaw_marl.evaluation.evaluate import run_episode
    from rtaw_marl.integrations.lorr.output import write_episode
    from rtaw_marl.policies import make_baseline
    from rtaw_marl.scenarios.lorr import lorr_scenario
    from rtaw_marl.sim.builder import build_sim

    sim = build_sim(lorr_scenario(RANDOM, horizon=120).spec())
    policy = make_baseline("batch")
    finished = run_episode(sim, policy, 3).tasks_finished
    path = write_episode(sim.schedule(), tmp_path / "episode.json", horizon=120)
    again = read_replay(path, sim.layout)
    assert again.tasks_finished == finished > 0
    np.testing.assert_array_equal(again.positions, sim.schedule().positions[:121, :, ::-1])


@needs_kit
def test_a_failing_scheduler_is_one_clear_error(build: KitBuild, tmp_path: Path) -> None:
    """A policy that cannot load inside lifelong: its error, not a crash log."""
    spec = _spec("checkpoint", source=str(tmp_path / "missing.pt"))
    with pytest.raises(StartKitError, match="scheduler failed inside lifelong"):
        run_lifelong(build, RANDOM, tmp_path / "run", spec, "broken", 5, PLAN_MS)


@needs_kit
def test_rtaw_lorr_cli(build: KitBuild, tmp_path: Path) -> None:
    """rtaw-lorr runs a scheduler and writes results.json; bad input exits 2 in one line."""
    out = tmp_path / "r.json"
    done = subprocess.run(
        [sys.executable, "-m", "rtaw_marl.cli.lorr", f"problem={RANDOM}", "policy=mpdm",
         "timesteps=30", "plan_time_ms=30", f"output={out}", f"hydra.run.dir={tmp_path}/run"],
        capture_output=True, text=True,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    runs = json.loads(out.read_text())["runs"]
    assert runs["mpdm"]["schedule_errors"] == 0
    assert runs["mpdm"]["timesteps"] == 30
    for bad, message in [
        ("problem=/nonexistent.json", "LoRR problem file not found"),
        ("policy=hindsight", "hindsight needs the episode's future"),
        ("policy=mpdmm", "unknown policy"),
        ("policy=pretrained", "needs pretrained="),
        ("policy=matched matched=generalist_plus", "policy=matched needs candidates=K"),
        ("pretrained=generalist_plus", "pretrained=... given but policy does not include"),
        ("planner=astar", "planner must be one of default, pibt"),
        ("planner=pibt", "planner=pibt runs under the kit's default scheduler"),
    ]:
        args = [f"problem={RANDOM}", *bad.split()] if not bad.startswith("problem") else [bad]
        done = subprocess.run(
            [sys.executable, "-m", "rtaw_marl.cli.lorr", *args, f"hydra.run.dir={tmp_path}/x"],
            capture_output=True, text=True,
        )  # fmt: skip
        assert done.returncode == 2, (bad, done.stderr)
        assert message in done.stderr
        assert "Traceback" not in done.stderr
        assert len(done.stderr.strip().splitlines()) == 1


def test_rtaw_lorr_runs_a_user_policy(build: KitBuild, tmp_path: Path) -> None:
    """``policy=my_rules:first_queued``: the user's module, imported from the command's
    working directory inside LoRR's own process, schedules; its label is the name."""
    (tmp_path / "my_rules.py").write_text(
        "import numpy as np\n\n\ndef first_queued(sim):\n"
        "    return int(np.flatnonzero(sim.queue_mask)[0])\n"
    )
    out = tmp_path / "r.json"
    done = subprocess.run(
        [sys.executable, "-m", "rtaw_marl.cli.lorr", f"problem={RANDOM}",
         "policy=[mpdm,my_rules:first_queued]", "timesteps=30", "plan_time_ms=30",
         f"output={out}", f"hydra.run.dir={tmp_path}/run"],
        capture_output=True, text=True, cwd=tmp_path,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    runs = json.loads(out.read_text())["runs"]
    assert set(runs) == {"mpdm", "first_queued"}
    assert runs["first_queued"]["schedule_errors"] == 0
    assert runs["first_queued"]["timesteps"] == 30
    bad = subprocess.run(
        [sys.executable, "-m", "rtaw_marl.cli.lorr", f"problem={RANDOM}",
         "policy=my_rules:last_queued", f"hydra.run.dir={tmp_path}/x"],
        capture_output=True, text=True, cwd=tmp_path,
    )  # fmt: skip
    assert bad.returncode == 2
    assert "my_rules has no 'last_queued'" in bad.stderr
    assert len(bad.stderr.strip().splitlines()) == 1


def test_missing_kit_and_packages_are_clear(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    with pytest.raises(StartKitError, match="not found at"):
        kit_source(tmp_path)
    monkeypatch.setattr(kit_module, "missing_packages", lambda: ["libboost-log-dev"])
    # The library never installs system packages, root or not: it names the command.
    calls: list[list[str]] = []
    monkeypatch.setattr(kit_module.subprocess, "run", lambda cmd, **_: calls.append(cmd))
    with pytest.raises(StartKitError, match=r"apt-get install -y .*libboost-log-dev"):
        kit_module.check_system_packages()
    assert calls == []


def test_the_makefile_asks_the_kit_what_to_install(capsys: pytest.CaptureFixture[str]) -> None:
    """``make lorr-kit`` installs what ``--missing`` prints (nothing, on a ready machine)."""
    kit_module.main(["--missing"])
    printed = capsys.readouterr().out.split()
    assert printed == kit_module.missing_packages()
    with pytest.raises(SystemExit) as exit_info:
        kit_module.main(["--mising"])
    assert exit_info.value.code == 2
    with pytest.raises(StartKitError, match="unknown start kit build"):
        build_kit("gpu")


def test_replay_catches_bad_outputs() -> None:
    """The checker refuses what LoRR would: a blocked cell, a shared cell, a swap, an
    event away from its errand (the one reader of the format, as rtaw-view reads it)."""
    from rtaw_marl.sim.layout import Layout

    layout = Layout(np.array([[0, 0, 0], [0, 1, 0]], dtype=bool))
    base = {"actionModel": "MAPF", "start": [[0, 0, "N/A"], [0, 2, "N/A"]], "events": [],
            "tasks": [[0, 0, [0, 1, 0, 2]]], "actualSchedule": ["", ""], "teamSize": 2,
            "numTaskFinished": 0}  # fmt: skip
    assert replay({**base, "actualPaths": ["R,W", "W,W"]}, layout).tasks_finished == 0
    with pytest.raises(ConfigError, match="an obstacle, at timestep 2"):
        replay({**base, "actualPaths": ["R,U", "W,W"]}, layout)  # U: row + 1, onto (1, 1)
    with pytest.raises(ConfigError, match="share a cell"):
        replay({**base, "actualPaths": ["R,W", "L,W"]}, layout)
    with pytest.raises(ConfigError, match="swap"):
        replay({**base, "start": [[0, 0, "N/A"], [0, 1, "N/A"]], "actualPaths": ["R", "L"]}, layout)
    with pytest.raises(ConfigError, match="not at errand 1 of task 0"):
        replay({**base, "actualPaths": ["W", "W"], "events": [[1, 0, 0, 1]],
                "actualSchedule": ["0:0", ""]}, layout)  # fmt: skip
    finished = replay(
        {**base, "start": [[0, 0, "E"], [1, 2, "N"]], "actionModel": "MAPF_T",
         "actualPaths": ["F,F", "W,W"], "events": [[1, 0, 0, 1], [2, 0, 0, 2]],
         "actualSchedule": ["0:0", ""], "numTaskFinished": 1}, layout,
    )  # fmt: skip
    assert finished.tasks_finished == 1
