"""The viewer at warehouse scale, in a real browser: a map of ``warehouse_large``'s
500 x 140 cells with 1,000 and 10,000 robots, two episodes. At fit the panels are
stacked and fill the screen, and the congestion overlay is visible: every block of cells
with congestion is drawn in the congestion colour (the whole block, not only the cell),
blocks without none. Also the difference of the two episodes, the robots' headings and
the throughput chart's window.

The episodes are synthetic (60 timesteps, built here with known congestion), so that a
page of 10,000 robots costs seconds: busy robots standing still on a sparse lattice of
cells (congestion, in different places in the two episodes), busy robots moving back
and forth (no congestion), idle robots standing still (not congestion).
"""

from __future__ import annotations

import io
import math
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from PIL import Image

from rtaw_marl.sim.layout import Layout
from rtaw_marl.sim.mapf.schedule import Schedule
from rtaw_marl.viz.view import ViewEpisode, write_view
from tests.viz.browser import browser_or_skip, chromium, open_view, severe_logs

pytestmark = pytest.mark.system

WIDTH, HEIGHT, STEPS = 500, 140, 60
#: The lattice of congested cells: every SPACING-th cell of a region, per episode.
SPACING = 6
JAMS = ((60, 20, 240, 80), (260, 70, 440, 130))  # x0, y0, x1, y1 of episode 0, 1
MOVERS = (300, 2, 480, 40)  # busy robots moving back and forth (both episodes)
WINDOW = (1600, 900)


def _lattice(x0: int, y0: int, x1: int, y1: int, step: int) -> np.ndarray:
    xs, ys = np.meshgrid(np.arange(x0, x1, step), np.arange(y0, y1, step))
    return np.column_stack([xs.ravel(), ys.ravel()])


def synthetic(robots: int, jam: int, headings: bool = False) -> Schedule:
    """``robots`` on the 500 x 140 grid for :data:`STEPS` timesteps: the jam lattice of
    :data:`JAMS` ``[jam]`` stands still with tasks, :data:`MOVERS` move with tasks
    (delivered at 20..59, then idle), the rest stand idle on cells of their own."""
    jammed = _lattice(*JAMS[jam], SPACING)
    movers = _lattice(*MOVERS, 2)[: robots // 10]
    used = np.zeros((HEIGHT, WIDTH), dtype=bool)
    for cells in (jammed, movers, movers + np.array([1, 0])):
        used[cells[:, 1], cells[:, 0]] = True
    free = np.argwhere(~used)[:, ::-1]
    rest = free[np.linspace(0, len(free) - 1, robots - len(jammed) - len(movers)).astype(int)]
    start = np.concatenate([jammed, movers, rest])
    positions = np.repeat(start[None], STEPS + 1, axis=0).astype(np.int64)
    a, b = len(jammed), len(jammed) + len(movers)
    positions[1::2, a:b, 0] += 1  # +x on odd timesteps, back on even ones
    busy = np.arange(b)
    delivered = np.where(busy < a, STEPS + 1, 20 + busy % 40)
    return Schedule(
        positions=positions,
        tasks=np.zeros((b, 4), dtype=np.int64),
        task_robot=busy,
        task_arrival=np.zeros(b, dtype=np.int64),
        task_assigned=np.zeros(b, dtype=np.int64),
        task_pickup=np.where(busy < a, STEPS + 1, 10),
        task_delivered=delivered,
        headings=np.tile(np.arange(robots) % 4, (STEPS + 1, 1)) if headings else None,
        task_ids=1000 + busy,
    )


@pytest.fixture(scope="module", params=[1_000, 10_000], ids=["1k", "10k"])
def large(request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory) -> Any:
    """A page of two synthetic episodes, open at fit in a 1600 x 900 window."""
    browser_or_skip()
    robots = int(request.param)
    layout = Layout(np.zeros((HEIGHT, WIDTH), dtype=bool), name="wide")
    eps = [ViewEpisode(f"e{j}", synthetic(robots, j, headings=True)) for j in (0, 1)]
    path = tmp_path_factory.mktemp("large") / "view.html"
    write_view(path, layout, eps, "large")
    with chromium(*WINDOW) as driver:
        open_view(driver, path)
        yield driver


def _shot(driver: Any) -> np.ndarray:
    return np.asarray(Image.open(io.BytesIO(driver.get_screenshot_as_png())).convert("RGB"))


def _panels(driver: Any) -> list[dict[str, float]]:
    return driver.execute_script(
        "return [...document.querySelectorAll('.panel canvas')]"
        ".map(c => c.getBoundingClientRect().toJSON())"
    )


def _red(rgb: np.ndarray) -> np.ndarray:
    """The congestion colour (or the difference's first-episode colour) over anything."""
    r, g, b = (rgb[..., i].astype(int) for i in range(3))
    return (r > 180) & (g < 90) & (b < 90)


def _blue(rgb: np.ndarray) -> np.ndarray:
    """The difference's second-episode colour over anything."""
    r, b = rgb[..., 0].astype(int), rgb[..., 2].astype(int)
    return (b > 180) & (r < 90)


def _pixels(driver: Any, panel: int, cells: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Screen pixels ``(row, column)`` of the points ``cells [N, 2]`` (in cells) of
    ``panel``."""
    scale, (cx, cy) = driver.execute_script(
        f"return [window.rtawView.state().scale, window.rtawView.cellToClient({panel}, 0, 0)]"
    )
    x = np.floor(cx - scale / 2 + cells[:, 0] * scale).astype(int)
    y = np.floor(cy - scale / 2 + cells[:, 1] * scale).astype(int)
    return y, x


def _block_mates(cells: np.ndarray, k: int) -> np.ndarray:
    """For each cell, the cell of its k x k block farthest from it (another cell)."""
    corner = (cells // k) * k
    return np.where(cells % k == 0, corner + k - 1, corner)


def test_panels_stack_and_fill_the_screen(large: Any) -> None:
    driver = large
    driver.execute_script("window.rtawView.fit()")
    state = driver.execute_script("return window.rtawView.state()")
    top, bottom = _panels(driver)
    box = driver.execute_script(
        "return document.getElementById('panels').getBoundingClientRect().toJSON()"
    )
    assert bottom["top"] >= top["bottom"] - 1  # one above the other
    assert state["stacked"]
    for rect in (top, bottom):
        assert rect["width"] >= box["width"] - 2
        assert rect["height"] >= box["height"] / 2 - 2
    side_by_side = min(box["width"] / 2 / WIDTH, box["height"] / HEIGHT)
    assert state["scale"] > 1.5 * side_by_side
    assert WIDTH * state["scale"] >= 0.98 * top["width"]  # the map spans the panel
    assert driver.execute_script("return window.rtawErrors") == []
    assert severe_logs(driver) == []


def test_congestion_is_visible_at_fit_in_blocks(large: Any) -> None:
    """Each jam cell's block is in the congestion colour at a cell of the block that has
    no congestion itself (a per-cell overlay leaves it blank); cells of blocks without
    congestion (the movers, idle robots, free cells) are not."""
    driver = large
    driver.execute_script("window.rtawView.fit(); window.rtawView.seek(30)")
    driver.execute_script("window.rtawView.setOverlay('heat')")
    state = driver.execute_script("return window.rtawView.state()")
    k = state["heatBlock"][0]
    assert k >= 2
    assert k * state["scale"] >= 3
    shot = _shot(driver)
    for panel in (0, 1):
        jam = _lattice(*JAMS[panel], SPACING)
        y, x = _pixels(driver, panel, _block_mates(jam, k) + 0.5)
        assert _red(shot[y, x]).all(), panel
        quiet = np.concatenate([_lattice(*JAMS[1 - panel], SPACING), _lattice(*MOVERS, 2)])
        y, x = _pixels(driver, panel, quiet + 0.5)
        assert not _red(shot[y, x]).any(), panel
    # The minimaps: blocks of at least 3 pixels in their 300-pixel width.
    minis = driver.execute_script(
        "return [...document.querySelectorAll('#heatmaps canvas')].map(c => "
        "[c.width, c.getBoundingClientRect().width])"
    )
    assert all(shown / width >= 3 for width, shown in minis)
    driver.execute_script("window.rtawView.setOverlay('none')")


def test_difference_colours_each_episodes_jam(large: Any) -> None:
    """A - B: the first episode's jam red, the second's blue, in both panels."""
    driver = large
    driver.execute_script("window.rtawView.fit(); window.rtawView.seek(30)")
    driver.execute_script("window.rtawView.setOverlay('diff')")
    k = driver.execute_script("return window.rtawView.state()")["heatBlock"][0]
    shot = _shot(driver)
    for panel in (0, 1):
        for jam, colour in ((0, _red), (1, _blue)):
            cells = _block_mates(_lattice(*JAMS[jam], SPACING), k) + 0.5
            y, x = _pixels(driver, panel, cells)
            assert colour(shot[y, x]).all(), (panel, jam)
    driver.execute_script("window.rtawView.setOverlay('none')")


def test_headings_point_where_robots_face(large: Any) -> None:
    """Zoomed in (40 pixels a cell), a robot of heading h (robot % 4: east, south, west,
    north) has the light bar ahead of its centre and its state's colour behind."""
    driver = large
    driver.execute_script("window.rtawView.seek(0)")
    driver.execute_script("window.rtawView.setCamera(40, -40 * 150, -40 * 38)")
    schedule = synthetic(int(driver.execute_script("return window.rtawView.state().robots[0]")), 0)
    cells = schedule.positions[0]
    scale = 40
    shot = _shot(driver)
    rect = _panels(driver)[0]
    seen = set()
    for robot in np.flatnonzero(
        (cells[:, 0] > 151) & (cells[:, 0] < 181) & (cells[:, 1] > 40) & (cells[:, 1] < 48)
    ):
        h = int(robot % 4)
        dx, dy = math.cos(h * math.pi / 2), math.sin(h * math.pi / 2)
        cx, cy = driver.execute_script(
            f"return window.rtawView.cellToClient(0, {cells[robot, 0]}, {cells[robot, 1]})"
        )
        if not (rect["left"] < cx < rect["right"] and rect["top"] < cy < rect["bottom"] - 40):
            continue
        ahead = shot[round(cy + 0.25 * scale * dy), round(cx + 0.25 * scale * dx)]
        behind = shot[round(cy - 0.25 * scale * dy), round(cx - 0.25 * scale * dx)]
        assert (ahead > 200).all(), (robot, h, ahead)
        assert not (behind > 200).all(), (robot, h, behind)
        seen.add(h)
    assert seen == {0, 1, 2, 3}


def test_throughput_window(large: Any) -> None:
    """The chart is the mean of deliveries per timestep over the chosen window, centred."""
    driver = large
    assert driver.execute_script("return window.rtawView.state().tpWindow") == 1  # 60 / 50
    driver.execute_script("window.rtawView.setWindow(10)")
    series = driver.execute_script("return window.rtawView.throughput()")
    width = len(series[0])
    robots = driver.execute_script("return window.rtawView.state().robots[0]")
    delivered = np.bincount(synthetic(robots, 0).task_delivered, minlength=STEPS + 2)
    done = np.concatenate([[0], np.cumsum(delivered[: STEPS + 1])])
    for x in (0, width // 3, width // 2, width - 1):
        t = x / (width - 1) * STEPS
        lo = max(0, round(t - 5))
        hi = min(STEPS + 1, max(lo + 1, round(t + 5)))
        assert series[0][x] == pytest.approx((done[hi] - done[lo]) / (hi - lo)), x
    driver.execute_script("window.rtawView.setWindow(1)")


def test_a_square_map_keeps_panels_side_by_side(tmp_path: Path) -> None:
    """Two episodes on a square map: side by side gives larger cells; in a tall window,
    stacked does, and a resize changes the layout (and refits the map)."""
    browser_or_skip()
    layout = Layout(np.zeros((HEIGHT, HEIGHT), dtype=bool), name="square")
    still = Schedule(
        np.array([[[0, 0], [5, 5]]] * 3), np.zeros((0, 4), dtype=np.int64),
        *(np.zeros(0, dtype=np.int64) for _ in range(5)),
    )  # fmt: skip
    eps = [ViewEpisode("a", still), ViewEpisode("b", still)]
    path = write_view(tmp_path / "v.html", layout, eps, "square")
    with chromium(*WINDOW) as driver:
        open_view(driver, path)
        left, right = _panels(driver)
        assert not driver.execute_script("return window.rtawView.state().stacked")
        assert right["left"] >= left["right"] - 1
        wide = driver.execute_script("return window.rtawView.state().scale")
        driver.set_window_size(700, 1600)
        time.sleep(0.3)  # the resize event, then a frame
        top, bottom = _panels(driver)
        state = driver.execute_script("return window.rtawView.state()")
        assert state["stacked"]
        assert bottom["top"] >= top["bottom"] - 1
        assert state["scale"] == pytest.approx(min(top["width"], top["height"]) / HEIGHT)
        assert state["scale"] != pytest.approx(wide)
