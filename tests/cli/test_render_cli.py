"""rtaw-render: one episode with a collision-aware navigator, checked and saved as a GIF."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
from hydra import compose, initialize_config_dir
from PIL import Image

from rtaw_marl.cli import CONF_DIR
from rtaw_marl.cli.render import run

RTAW_RENDER = Path(sys.executable).with_name("rtaw-render")


@pytest.mark.parametrize("navigator", ["sipp", "cbs"])
def test_render_writes_a_checked_gif(navigator: str, tmp_path: Path) -> None:
    """A short episode on layout A with the shipped policy: one frame per second."""
    out = tmp_path / "episode.gif"
    overrides = [
        f"navigator={navigator}", "layout=A", "env.num_tasks=6", "policy=rtaw",
        "pretrained=A_astar_m10", f"output={out}", "every=2",
    ]  # fmt: skip
    with initialize_config_dir(config_dir=str(CONF_DIR), version_base="1.3"):
        cfg = compose(config_name="render", overrides=overrides)
    assert run(cfg) == out
    with Image.open(out) as gif:
        frames = gif.n_frames
        assert gif.size[0] == 600
    assert frames > 10
    assert not list(tmp_path.glob(".*tmp"))


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["navigator=astar"], "render with navigator=sipp or navigator=cbs"),
        (["policy=[mpdm,rbts]"], "policy must name one policy"),
        (["output=out.png"], "must end in .gif"),
        (["max_frames=3"], "max_frames"),
    ],
)
def test_render_errors_are_one_line(args: list[str], message: str, tmp_path: Path) -> None:
    proc = subprocess.run(
        [str(RTAW_RENDER), "env.num_tasks=4", *args], cwd=tmp_path, capture_output=True,
        text=True, timeout=300,
    )  # fmt: skip
    assert proc.returncode == 2
    assert message in proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1
    assert "Traceback" not in proc.stderr + proc.stdout
