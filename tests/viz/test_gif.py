"""GIF rendering of an executed schedule: frames, sizes, colours, argument checks."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from rtaw_marl.errors import ConfigError
from rtaw_marl.sim.layout import Layout
from rtaw_marl.sim.mapf.schedule import Schedule
from rtaw_marl.viz.gif import BASE_COLORS, HEADER_PX, render_gif, robot_color

pytestmark = pytest.mark.unit

W, H, T = 8, 6, 14


def _path(cells: list[tuple[int, int]]) -> list[tuple[int, int]]:
    return cells + [cells[-1]] * (T + 1 - len(cells))


@pytest.fixture
def layout() -> Layout:
    grid = np.zeros((H, W), dtype=bool)
    grid[5, 7] = grid[0, 7] = True
    return Layout(grid, name="tiny")


@pytest.fixture
def schedule() -> Schedule:
    """Robot 0 serves task 0 along the top row; robot 1 serves tasks 1 and 2 below."""
    r0 = _path([(x, 0) for x in range(6)] + [(5, y) for y in range(1, 4)])
    r1 = _path(
        [(x, 5) for x in range(7)] + [(6, 4), (5, 4), (4, 4), (3, 4), (2, 4), (1, 4), (0, 4)]
    )
    return Schedule(
        positions=np.array([r0, r1], dtype=np.int64).transpose(1, 0, 2),
        tasks=np.array([[2, 0, 5, 3], [4, 5, 6, 5], [1, 4, 0, 4]], dtype=np.int64),
        task_robot=np.array([0, 1, 1]),
        task_arrival=np.array([0, 1, 3]),
        task_assigned=np.array([1, 2, 10]),
        task_pickup=np.array([2, 4, 12]),
        task_delivered=np.array([8, 6, 13]),
    )


def _frames(path: Path) -> list[np.ndarray]:
    with Image.open(path) as im:
        assert im.format == "GIF"
        out = []
        for i in range(im.n_frames):
            im.seek(i)
            out.append(np.asarray(im.convert("RGB")))
        return out


def _cell(frame: np.ndarray, x: int, y: int, c: int) -> set[tuple[int, int, int]]:
    block = frame[HEADER_PX + y * c : HEADER_PX + (y + 1) * c, x * c : (x + 1) * c]
    return {tuple(int(v) for v in px) for px in block.reshape(-1, 3)}


def test_frames_size_and_colours(tmp_path: Path, layout: Layout, schedule: Schedule) -> None:
    c = 10
    out = render_gif(layout, schedule, tmp_path / "ep.gif", cell_px=c, title="tiny")
    assert out == tmp_path / "ep.gif"
    with Image.open(out) as im:
        assert im.size == (W * c, H * c + HEADER_PX)
        assert abs(im.info["duration"] - 125) < 10  # GIF stores centiseconds
    frames = _frames(out)
    assert len(frames) == T + 1
    for t, frame in enumerate(frames):
        for m in range(2):
            x, y = schedule.positions[t, m]
            centre = frame[HEADER_PX + y * c + c // 2, x * c + c // 2]
            assert tuple(centre) == robot_color(m), (t, m)
        assert tuple(frame[HEADER_PX + 5 * c + c // 2, 7 * c + c // 2]) == BASE_COLORS["obstacle"]
    queued, box = BASE_COLORS["queued"], BASE_COLORS["box"]
    # Task 0: queued at t=0, robot 0 on its way at t=1, carried from t=2, delivered at t=8.
    assert queued in _cell(frames[0], 2, 0, c)
    assert robot_color(0) in _cell(frames[1], 2, 0, c)
    assert queued not in _cell(frames[1], 2, 0, c)
    assert robot_color(0) in _cell(frames[3], 5, 3, c)  # the X on the destination
    assert box in _cell(frames[3], 3, 0, c)  # the box on robot 0
    assert _cell(frames[8], 2, 0, c) <= {BASE_COLORS["free"], BASE_COLORS["gridline"]}
    assert box not in _cell(frames[8], 5, 3, c)


@pytest.mark.parametrize(
    ("kwargs", "times"),
    [
        ({"start": 2, "stop": 11, "every": 3}, [2, 5, 8, 11]),
        ({"start": 4}, list(range(4, T + 1))),
        ({"stop": 3, "every": 2}, [0, 2]),
        ({"start": 6, "stop": 6}, [6]),
    ],
)
def test_start_stop_every(
    tmp_path: Path, layout: Layout, schedule: Schedule, kwargs: dict, times: list[int]
) -> None:
    c = 6
    frames = _frames(render_gif(layout, schedule, tmp_path / "ep.gif", cell_px=c, **kwargs))
    assert len(frames) == len(times)
    for frame, t in zip(frames, times, strict=True):
        x, y = schedule.positions[t, 1]
        assert tuple(frame[HEADER_PX + y * c + c // 2, x * c + c // 2]) == robot_color(1)


def test_default_cell_size_with_labels(tmp_path: Path, layout: Layout, schedule: Schedule) -> None:
    out = render_gif(layout, schedule, tmp_path / "ep.gif", fps=4, title="labelled")
    with Image.open(out) as im:
        assert im.size == (W * 75, H * 75 + HEADER_PX)
        assert im.n_frames == T + 1
        assert im.info["duration"] == 250


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"fps": 0}, "fps"),
        ({"every": 0}, "every"),
        ({"cell_px": 0}, "cell_px"),
        ({"max_frames": 0}, "max_frames"),
        ({"start": -1}, "start"),
        ({"start": T + 1}, "start"),
        ({"stop": T + 1}, "stop"),
        ({"start": 5, "stop": 4}, "stop"),
        ({"path": "ep.png"}, "path"),
        ({"layout": Layout(np.zeros((4, 4), dtype=bool))}, "schedule"),
    ],
)
def test_bad_arguments(
    tmp_path: Path, layout: Layout, schedule: Schedule, kwargs: dict, name: str
) -> None:
    args = {"layout": layout, "schedule": schedule, "path": "ep.gif", **kwargs}
    args["path"] = tmp_path / args["path"]
    with pytest.raises(ConfigError, match=rf"\b{name}\b"):
        render_gif(**args)
    assert list(tmp_path.iterdir()) == []


def test_too_many_frames(tmp_path: Path, layout: Layout, schedule: Schedule) -> None:
    with pytest.raises(ConfigError, match=r"15 frames.*max_frames=10.*every=2.*stop="):
        render_gif(layout, schedule, tmp_path / "ep.gif", max_frames=10)
    assert list(tmp_path.iterdir()) == []
    frames = _frames(render_gif(layout, schedule, tmp_path / "ep.gif", max_frames=8, every=2))
    assert len(frames) == 8


def test_overwrite_is_atomic(tmp_path: Path, layout: Layout, schedule: Schedule) -> None:
    target = tmp_path / "ep.gif"
    target.write_bytes(b"not a gif")
    render_gif(layout, schedule, target, cell_px=4)
    assert len(_frames(target)) == T + 1
    render_gif(layout, schedule, target, cell_px=4, every=5)
    assert len(_frames(target)) == 3
    assert [p.name for p in tmp_path.iterdir()] == ["ep.gif"]


def test_header_lines_fit_the_picture(layout: Layout, schedule: Schedule, tmp_path: Path) -> None:
    """The title has its own line; a line wider than the picture ends in an ellipsis
    instead of running off its edge (a 100-robot title used to be cut off)."""
    from rtaw_marl.viz.gif import _font, fit_text

    font = _font(12)
    long = "generalist_plus@k32 | sipp | layout_A_60x60 | seed 0   " * 3
    fitted = fit_text(long, font, 200)
    assert fitted.endswith("…")
    assert font.getlength(fitted) <= 200
    assert long.startswith(fitted[:-1])
    assert fit_text("t = 3 s", font, 200) == "t = 3 s"
    out = render_gif(layout, schedule, tmp_path / "t.gif", cell_px=10, title=long)
    with Image.open(out) as im:
        header = np.asarray(im.convert("RGB"))[:HEADER_PX]
    dark = np.flatnonzero((header.sum(axis=-1) < 300).any(axis=1))
    assert dark.min() < 17 < dark.max()  # text on both lines
