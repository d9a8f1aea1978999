"""rtaw-view: episodes played (or read from LoRR output files), checked, written as one
self-contained HTML page; one-line errors."""

from __future__ import annotations

import base64
import json
import re
import zlib
from pathlib import Path

import numpy as np
import pytest

from rtaw_marl.cli.render import run as render
from rtaw_marl.cli.view import run
from rtaw_marl.config import compose
from rtaw_marl.viz.episode_data import MOVES
from tests.cli.test_eval_cli import _tiny_lorr_problem
from tests.viz.saved_files import valid, write

pytestmark = pytest.mark.integration


def _episodes(path: Path) -> list[dict]:
    text = path.read_text(encoding="utf-8")
    match = re.search(r'<script id="rtaw-data" type="application/json">(.*?)</script>', text, re.S)
    assert match is not None
    return json.loads(match.group(1))["episodes"]


def _positions(ep: dict) -> np.ndarray:
    def array(key: str) -> np.ndarray:
        entry = ep[key]
        raw = zlib.decompress(base64.b64decode(entry["data"]))
        return np.frombuffer(raw, dtype=entry["dtype"]).reshape(entry["shape"])

    steps = np.array(MOVES)[array("moves").T]  # sent [M, T]
    start = array("start")
    return np.concatenate([start[None], start[None] + steps.cumsum(0)])


def test_two_policies_side_by_side(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    out = tmp_path / "v.html"
    overrides = ["layout=A", "sim.num_tasks=6", "policy=[mpdm,pretrained]",
                 "pretrained=A_astar_m10", f"output={out}"]  # fmt: skip
    assert run(compose(config_name="view", overrides=overrides)) == out
    captured = capsys.readouterr()
    names = [ep["name"] for ep in _episodes(out)]
    assert names == ["mpdm", "A_astar_m10"]
    assert "mpdm: TTD" in captured.out
    assert f"viewer: {out}" in captured.out
    assert "packing mpdm: 10 robots" in captured.err  # progress on stderr
    assert not list(tmp_path.glob(".*tmp"))


def test_saved_lorr_output_is_shown(tmp_path: Path) -> None:
    """rtaw-render output=*.json, then rtaw-view schedule=: the same robot positions."""
    problem = _tiny_lorr_problem(tmp_path)
    saved = tmp_path / "episode.json"
    scenario = ["scenario=lorr", f"tasks.problem={problem}", "sim.horizon=40"]
    render(
        compose(config_name="render", overrides=[*scenario, "sim.num_tasks=200", f"output={saved}"])
    )
    out = tmp_path / "v.html"
    run(compose(config_name="view", overrides=[*scenario, f"schedule={saved}", f"output={out}"]))
    (ep,) = _episodes(out)
    assert ep["name"] == "episode"
    paths = json.loads(saved.read_text())["actualPaths"]
    assert ep["steps"] == len(paths[0].split(","))
    pos = _positions(ep)
    start = json.loads(saved.read_text())["start"]
    assert pos[0].tolist() == [[c, r] for r, c, _ in start]
    assert ep["summary"]["tasks finished"] == json.loads(saved.read_text())["numTaskFinished"]
    # The page's task ids are the file's (the played episode's stream ids).
    entry = ep["tasks"]
    rows = np.frombuffer(zlib.decompress(base64.b64decode(entry["data"])), dtype=entry["dtype"])
    ids = rows.reshape(entry["shape"])[:, 9]
    assert sorted(ids.tolist()) == sorted(t[0] for t in json.loads(saved.read_text())["tasks"])


@pytest.mark.parametrize("app", ["view", "render"])
def test_a_lorr_scenario_keeps_its_task_count(app: str, tmp_path: Path) -> None:
    """The apps' short default (50 tasks) does not cut a horizon episode's task count."""
    problem = _tiny_lorr_problem(tmp_path)
    cfg = compose(config_name=app, overrides=["scenario=lorr", f"tasks.problem={problem}"])
    assert cfg.sim.num_tasks != 50
    assert compose(config_name=app, overrides=[]).sim.num_tasks == 50


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["navigator=astar"], "view with navigator=sipp, cbs or pibt"),
        (["output=out.gif"], "output must end in .html, got 'out.gif'"),
        (["policy=[mpdm,rbts,random]"], "policy must be one name or a list of two"),
        (["policy=[mpdm,mpdm]"], "policy names the same policy twice"),
        (["schedule=missing.json"], "schedule=missing.json: no such file"),
    ],
)
def test_view_errors_are_one_line(args: list[str], message: str, cli) -> None:
    result = cli("view", "sim.num_tasks=4", *args)
    assert result.code == 2
    assert message in result.err
    assert len(result.err.strip().splitlines()) == 1
    assert "Traceback" not in result.err + result.out


# --------------------------------------------------------------- saved files, outputs
def _saved_setup(root: Path, name: str = "s.json") -> tuple[list[str], Path]:
    """The tiny LoRR problem and a valid saved episode on its map, in ``root``."""
    problem = _tiny_lorr_problem(root)
    saved = write(root / name, valid())
    return ["scenario=lorr", f"tasks.problem={problem.name}", f"schedule={saved.name}"], saved


def _one_line_error(result, message: str) -> None:
    assert result.code == 2
    assert message in result.err
    assert len(result.err.strip().splitlines()) == 1
    assert "Traceback" not in result.err + result.out


def _leftovers(root: Path) -> list[str]:
    """Locks and temporary files a run left beside its output."""
    return sorted(p.name for p in root.glob(".*") if p.suffix in (".lock", ".tmp"))


@pytest.mark.parametrize("form", ["same name", "relative", "symlink", "hard link"])
def test_view_never_overwrites_the_schedule_it_reads(form: str, tmp_path: Path, cli) -> None:
    """schedule=s.html output=s.html, however the output names that file: refused
    before any work, the schedule untouched."""
    args, saved = _saved_setup(tmp_path, "s.html")
    before = saved.read_bytes()
    output = {"same name": "s.html", "relative": "sub/../s.html", "symlink": "link.html",
              "hard link": "hard.html"}[form]  # fmt: skip
    (tmp_path / "sub").mkdir()
    (tmp_path / "link.html").symlink_to(saved)
    (tmp_path / "hard.html").hardlink_to(saved)
    result = cli("view", *args, f"output={output}")
    _one_line_error(result, f"output={output} is the same file as schedule=s.html, which this")
    assert saved.read_bytes() == before
    assert (tmp_path / "link.html").is_symlink()
    assert _leftovers(tmp_path) == []


def test_view_output_in_use_is_refused(tmp_path: Path, cli) -> None:
    """Another run holds v.html: this one stops at once instead of replacing its page."""
    from rtaw_marl.utils.runs import claim_file

    args, _ = _saved_setup(tmp_path)
    with claim_file(tmp_path / "v.html"):
        result = cli("view", *args, "output=v.html")
        _one_line_error(result, "output=v.html is in use by another running process")
        assert not (tmp_path / "v.html").exists()
    assert cli("view", *args, "output=v.html").code == 0  # released: a run goes ahead
    assert _leftovers(tmp_path) == []  # its lock is gone too


def test_view_removes_what_a_killed_write_left(tmp_path: Path, cli) -> None:
    """A kill -9 during the write leaves .v.html.XXXXXXXX.tmp: the next run removes it
    (and only it: another output's, and other names, are left alone)."""
    args, _ = _saved_setup(tmp_path)
    (tmp_path / "v.html").write_text("old page", encoding="utf-8")
    killed = tmp_path / ".v.html.k1ll_9ab.tmp"
    killed.write_bytes(b"\0" * 3_000_000)
    others = [".w.html.k1ll_9ab.tmp", ".v.html.short.tmp", "v.html.k1ll_9ab.tmp", ".v.html.lockx"]
    for name in others:
        (tmp_path / name).write_text("keep", encoding="utf-8")
    result = cli("view", *args, "output=v.html")
    assert result.code == 0, result.err
    assert not killed.exists()
    assert "removed what a killed earlier write of v.html left: .v.html.k1ll_9ab.tmp" in result.err
    assert all((tmp_path / name).read_text() == "keep" for name in others)
    assert "rtaw-data" in (tmp_path / "v.html").read_text(encoding="utf-8")
    assert not (tmp_path / ".v.html.lock").exists()


@pytest.mark.parametrize("name", ["__SCRIPT__", "__DATA__", "__STYLE__", "__TITLE__"])
def test_a_placeholder_file_name_stays_text(name: str, tmp_path: Path, cli) -> None:
    """A schedule named __SCRIPT__.json titles the page "__SCRIPT__": the viewer's code
    is in the page once, in its script element, not in the title."""
    args, _ = _saved_setup(tmp_path, f"{name}.json")
    result = cli("view", *args, "output=v.html")
    assert result.code == 0, result.err
    text = (tmp_path / "v.html").read_text(encoding="utf-8")
    assert f"<title>{name}</title>" in text
    assert text.count("window.rtawView =") == 1
    assert text.count('<script id="rtaw-data"') == 1
    (ep,) = _episodes(tmp_path / "v.html")
    assert ep["name"] == name


@pytest.mark.parametrize(
    ("content", "message"),
    [
        ({"start": [[0, 0, "N/A"], [2, 5, "Q"]]}, "schedule s.json: start[1] heading 'Q' is not"),
        ({"events": [[-1, 0, 0, 1]]}, "schedule s.json: events[0] timestep is -1"),
        ({"actualPaths": []}, "schedule s.json: actualPaths is empty"),
        ({"actualSchedule": ["0:abc", ""]}, "schedule s.json: actualSchedule[0] entry '0:abc'"),
        ("deep", "schedule s.json: is nested too deeply to be a LoRR output file"),
    ],
)
def test_a_bad_schedule_is_one_line_and_writes_nothing(
    content: dict | str, message: str, tmp_path: Path, cli
) -> None:
    args, saved = _saved_setup(tmp_path)
    if content == "deep":
        saved.write_text("[" * 200_000 + "]" * 200_000, encoding="utf-8")
    else:
        write(saved, {**valid(), **content})
    result = cli("view", *args, "output=v.html")
    _one_line_error(result, message)
    assert not (tmp_path / "v.html").exists()
    assert _leftovers(tmp_path) == []


# ------------------------------------------------------------------- memory estimate
BIG = ["layout=A", "sim.episode_mode=horizon", "sim.horizon=5000", "sim.num_robots=30000",
       "policy=[mpdm,lookahead]", "output=v.html"]  # fmt: skip


def test_a_view_that_cannot_fit_is_refused_before_work(
    tmp_path: Path, cli, monkeypatch: pytest.MonkeyPatch
) -> None:
    """30,000 robots, 5,000 timesteps, two policies, on a machine with 20 GB available:
    one line naming the settings to lower, before the simulator is built."""
    import rtaw_marl.viz.budget as budget

    monkeypatch.setattr(budget, "available_memory", lambda: 20 * 10**9)
    monkeypatch.setattr("rtaw_marl.cli.view.build_sim", lambda *a: pytest.fail("work started"))
    result = cli("view", *BIG)
    _one_line_error(result, "30,000 robots x 5,000 timesteps x 2 episodes needs about ")
    assert "more than the 20.0 GB available on this machine; lower sim.horizon (now 5000) " in (
        result.err
    )
    assert "or sim.num_robots (now 30000), or view one policy instead of 2" in result.err
    assert not (tmp_path / "v.html").exists()
    assert _leftovers(tmp_path) == []


def test_a_view_no_machine_holds_is_refused(tmp_path: Path, cli) -> None:
    """A setting of petabytes is refused on this machine as it is (nothing patched)."""
    result = cli("view", "layout=A", "sim.episode_mode=horizon", "sim.horizon=1000000000",
                 "sim.num_robots=10", "output=v.html")  # fmt: skip
    _one_line_error(result, "10 robots x 1,000,000,000 timesteps needs about 1,")
    assert "lower sim.horizon (now 1000000000)" in result.err
    assert not (tmp_path / "v.html").exists()


def test_a_small_view_is_not_refused_and_a_big_one_is_announced(
    tmp_path: Path, cli, monkeypatch: pytest.MonkeyPatch
) -> None:
    import rtaw_marl.viz.budget as budget

    monkeypatch.setattr(budget, "available_memory", lambda: 2 * 10**9)
    small = cli("view", "layout=A", "sim.num_tasks=4", "output=v.html")
    assert small.code == 0, small.err
    assert "estimate:" not in small.err
    monkeypatch.setattr(budget, "SHOWN_BYTES", 0)  # any run counts as big now
    shown = cli("view", "layout=A", "sim.num_tasks=4", "output=w.html")
    assert shown.code == 0, shown.err
    assert "estimate: 10 robots x " in shown.err
    assert "of memory (2.0 GB available) and about " in shown.err
