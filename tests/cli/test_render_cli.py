"""rtaw-render: one episode with a collision-aware navigator, checked and saved as a GIF."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
from PIL import Image

from rtaw_marl.cli.render import run
from rtaw_marl.config import compose

pytestmark = pytest.mark.integration

RTAW_RENDER = Path(sys.executable).with_name("rtaw-render")


@pytest.mark.parametrize("navigator", ["sipp", "cbs"])
def test_render_writes_a_checked_gif(navigator: str, tmp_path: Path) -> None:
    """A short episode on layout A with the shipped policy: one frame per second."""
    out = tmp_path / "episode.gif"
    overrides = [
        f"navigator={navigator}", "layout=A", "sim.num_tasks=6", "policy=pretrained",
        "pretrained=A_astar_m10", f"output={out}", "every=2",
    ]  # fmt: skip
    cfg = compose(config_name="render", overrides=overrides)
    assert run(cfg) == out
    with Image.open(out) as gif:
        frames = gif.n_frames
        assert gif.size[0] == 600
    assert frames > 10
    assert not list(tmp_path.glob(".*tmp"))


def test_render_writes_lorr_output(tmp_path: Path) -> None:
    """output=*.json: the checked episode in LoRR's output format, which replays to the
    episode's tasks finished (a LoRR problem, PIBT, 40 timesteps)."""
    from rtaw_marl.evaluation.evaluate import run_episode
    from rtaw_marl.integrations.lorr.output import read_replay
    from rtaw_marl.policies import make_baseline
    from rtaw_marl.scenarios.lorr import lorr_scenario
    from rtaw_marl.sim.builder import build_sim
    from rtaw_marl.sim.lorr import read_problem
    from tests.cli.test_eval_cli import _tiny_lorr_problem

    problem = _tiny_lorr_problem(tmp_path)
    out = tmp_path / "episode.json"
    overrides = ["scenario=lorr", f"tasks.problem={problem}", "sim.horizon=40",
                 "sim.num_tasks=200", f"output={out}"]  # fmt: skip
    cfg = compose(config_name="render", overrides=overrides)
    assert run(cfg) == out
    replayed = read_replay(out, read_problem(problem).layout())
    assert replayed.positions.shape == (41, 2, 2)
    # The same episode played directly: the replay counts what the simulator counted.
    sim = build_sim(lorr_scenario(problem, horizon=40, num_tasks=200).spec())
    played = run_episode(sim, make_baseline(cfg.policy), int(cfg.seed)).tasks_finished
    assert replayed.tasks_finished == played > 0


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["navigator=astar"], "render with navigator=sipp or navigator=cbs"),
        (["policy=[mpdm,rbts]"], "config key 'policy'"),
        (["output=out.png"], "must end in .gif"),
        (["max_frames=3"], "max_frames"),
    ],
)
def test_render_errors_are_one_line(args: list[str], message: str, cli) -> None:
    result = cli("render", "sim.num_tasks=4", *args)
    assert result.code == 2
    errors = [line for line in result.err.splitlines() if line.startswith("error:")]
    assert len(errors) == 1
    assert message in errors[0]
    assert result.err.strip().splitlines()[-1] == errors[0]
    assert "Traceback" not in result.err + result.out
    if args != ["max_frames=3"]:  # the frame count is known once the episode is played
        assert len(result.err.strip().splitlines()) == 1


def test_render_console_script_error_end_to_end(tmp_path: Path) -> None:
    """The installed console script: exit 2 and one line, in a fresh interpreter."""
    proc = subprocess.run(
        [str(RTAW_RENDER), "navigator=astar"], cwd=tmp_path, capture_output=True, text=True,
        timeout=300,
    )  # fmt: skip
    assert proc.returncode == 2
    assert proc.stderr.strip() == (
        "error: navigator=astar moves robots independently (they pass through each other); "
        "render with navigator=sipp or navigator=cbs"
    )


def _leftovers(root: Path) -> list[str]:
    """Locks and temporary files a run left beside its output."""
    return sorted(p.name for p in root.glob(".*") if p.suffix in (".lock", ".tmp"))


def test_render_never_overwrites_a_file_it_reads(tmp_path: Path, cli, monkeypatch) -> None:
    """output=P.json where P.json is the LoRR problem it plays: refused before work, the
    problem untouched (also through a symbolic link)."""
    from tests.cli.test_eval_cli import _tiny_lorr_problem

    problem = _tiny_lorr_problem(tmp_path)
    before = problem.read_bytes()
    (tmp_path / "link.json").symlink_to(problem)
    (tmp_path / "sub").mkdir()
    monkeypatch.setattr("rtaw_marl.cli.render.build_sim", lambda *a: pytest.fail("work started"))
    for output in ("p.json", "link.json", "sub/../p.json"):
        result = cli("render", "scenario=lorr", "tasks.problem=p.json", "sim.horizon=10",
                     f"output={output}")  # fmt: skip
        assert result.code == 2
        assert f"error: output={output} is the same file as " in result.err
        assert "problem=p.json, which this command reads" in result.err
        assert len(result.err.strip().splitlines()) == 1
        assert problem.read_bytes() == before
    assert _leftovers(tmp_path) == []


def test_render_output_in_use_is_refused(tmp_path: Path, cli, monkeypatch) -> None:
    """Another run holds episode.gif: this one stops before playing, writes nothing."""
    from rtaw_marl.utils.runs import claim_file

    monkeypatch.setattr("rtaw_marl.cli.render.build_sim", lambda *a: pytest.fail("work started"))
    with claim_file(tmp_path / "episode.gif"):
        result = cli("render", "sim.num_tasks=4", "output=episode.gif")
    assert result.code == 2
    assert "output=episode.gif is in use by another running process" in result.err
    assert len(result.err.strip().splitlines()) == 1
    assert not (tmp_path / "episode.gif").exists()
    assert _leftovers(tmp_path) == []


def test_render_removes_what_a_killed_write_left(tmp_path: Path, cli) -> None:
    """A killed earlier write's .e.json.XXXXXXXX.tmp goes; another output's stays; no
    lock is left after the run."""
    killed = tmp_path / ".e.json.a1b2c3d4.tmp"
    killed.write_text("half a file", encoding="utf-8")
    other = tmp_path / ".f.json.a1b2c3d4.tmp"
    other.write_text("keep", encoding="utf-8")
    result = cli("render", "layout=A", "sim.num_tasks=4", "output=e.json")
    assert result.code == 0, result.err
    assert not killed.exists()
    assert other.read_text(encoding="utf-8") == "keep"
    assert "removed what a killed earlier write of e.json left" in result.err
    assert (tmp_path / "e.json").stat().st_size > 0
    assert _leftovers(tmp_path) == [other.name]
