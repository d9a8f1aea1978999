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
