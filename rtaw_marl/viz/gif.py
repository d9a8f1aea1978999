"""Animated GIF of an executed episode (a :class:`~rtaw_marl.sim.mapf.schedule.Schedule`).

One frame per drawn time step ``t``. Legend:

* Header strip (:data:`HEADER_PX` pixels, white): the optional title on its own line,
  then ``t = 12 s`` and counters of the schedule's tasks that are queued, assigned
  (robot on its way to the origin), carried and delivered at ``t``; a title wider than
  the picture ends in an ellipsis. Tasks that were never assigned are not in
  a schedule, so they are not counted as queued.
* Cells: free light grey, obstacles dark slate, pickup stations light green, delivery
  stations light orange (when the layout has station masks); thin grid lines between
  free cells once a cell is at least 6 pixels wide.
* Robots: filled circles, one colour per robot (matplotlib's ``tab20`` without its
  greys, dark shades first; cycled past 18 robots), with the robot id once a cell is
  at least 14 pixels wide.
* Queued task (``arrival <= t < assigned``): small hollow grey square at its origin.
* Assigned task (``assigned <= t < pickup``): square at its origin outlined in the
  robot's colour, joined to the robot by a thin line of that colour.
* Carried task (``pickup <= t < delivered``): a brown box on the robot's top-right and
  an X in the robot's colour on the destination cell.
* Delivered tasks are not drawn.

Frames are drawn directly in palette mode with one fixed palette, so no per-frame
colour quantisation is needed.
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import BinaryIO

import numpy as np

from rtaw_marl.errors import ConfigError, missing_extra

# Without the command-line extra: one error that names it (errors.missing_extra), no traceback
# of a bare ModuleNotFoundError.
try:
    from matplotlib import colormaps
    from PIL import Image, ImageDraw, ImageFont, features
except ModuleNotFoundError as exc:
    raise missing_extra(exc, __name__, "cli") from None

from rtaw_marl.sim.layout import Layout
from rtaw_marl.sim.mapf.schedule import Schedule
from rtaw_marl.utils.atomic import atomic_write

__all__ = [
    "BASE_COLORS",
    "HEADER_PX",
    "ROBOT_COLORS",
    "fit_text",
    "render_gif",
    "robot_color",
]

HEADER_PX = 34
"""Height in pixels of the header strip above the grid (two lines of text)."""

BASE_COLORS: dict[str, tuple[int, int, int]] = {
    "header": (255, 255, 255),
    "free": (242, 242, 242),
    "obstacle": (58, 63, 75),
    "pickup": (204, 236, 204),
    "delivery": (252, 222, 190),
    "gridline": (222, 222, 222),
    "text": (20, 20, 20),
    "queued": (140, 140, 140),
    "box": (191, 142, 84),
    "box_edge": (92, 62, 30),
    "white": (255, 255, 255),
}
"""Fixed colours of everything except robots, in palette order."""

_TAB20 = [tuple(round(255 * c) for c in rgb[:3]) for rgb in colormaps["tab20"].colors]
ROBOT_COLORS: tuple[tuple[int, int, int], ...] = tuple(
    _TAB20[i] for i in [*range(0, 20, 2), *range(1, 20, 2)] if i not in (14, 15)
)
"""Robot colours (RGB), cycled by robot id."""

_IDX = {name: i for i, name in enumerate(BASE_COLORS)}
_ROBOT0 = len(BASE_COLORS)


def robot_color(robot: int) -> tuple[int, int, int]:
    """RGB colour of robot ``robot`` in a rendering."""
    return ROBOT_COLORS[robot % len(ROBOT_COLORS)]


def _check_int(name: str, value: object, minimum: int) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < minimum:
        raise ConfigError(f"{name} must be an integer >= {minimum}, got {value!r}")
    return int(value)


def _check_schedule(layout: Layout, s: Schedule) -> None:
    pos = np.asarray(s.positions)
    if pos.ndim != 3 or pos.shape[0] < 1 or pos.shape[2] != 2:
        raise ConfigError(f"schedule.positions must be [T + 1, M, 2], got shape {pos.shape}")
    k = len(s.tasks)
    if np.shape(s.tasks) != (k, 4) or any(
        np.shape(a) != (k,)
        for a in (s.task_robot, s.task_arrival, s.task_assigned, s.task_pickup, s.task_delivered)
    ):
        raise ConfigError(f"schedule task arrays must all have {k} rows (tasks is [K, 4])")
    cells = np.concatenate([pos.reshape(-1, 2), np.reshape(s.tasks, (-1, 2))])
    outside = ~layout.in_bounds(cells)
    if outside.any():
        x, y = (int(v) for v in cells[np.flatnonzero(outside)[0]])
        raise ConfigError(
            f"schedule does not match layout {layout.name!r} ({layout.width}x{layout.height}): "
            f"cell (x={x}, y={y}) is outside the grid"
        )
    if k and (np.min(s.task_robot) < 0 or np.max(s.task_robot) >= s.num_robots):
        raise ConfigError(f"schedule.task_robot must lie in [0, {s.num_robots})")


def _background(layout: Layout, c: int, width_px: int) -> Image.Image:
    cells = np.where(layout.obstacles, _IDX["obstacle"], _IDX["free"]).astype(np.uint8)
    for kind in ("pickup", "delivery"):
        mask = getattr(layout, kind)
        if mask is not None:
            cells[mask] = _IDX[kind]
    grid = np.kron(cells, np.ones((c, c), dtype=np.uint8))
    if c >= 6:
        edge = np.zeros((c, c), dtype=bool)
        edge[-1, :] = edge[:, -1] = True
        lines = np.kron(~layout.obstacles, edge).astype(bool)
        grid[lines] = _IDX["gridline"]
    header = np.full((HEADER_PX, width_px), _IDX["header"], dtype=np.uint8)
    img = Image.fromarray(np.vstack([header, grid]), mode="P")
    palette = [v for rgb in (*BASE_COLORS.values(), *ROBOT_COLORS) for v in rgb]
    img.putpalette(palette + [0] * (768 - len(palette)))
    return img


def _font(size: int) -> ImageFont.FreeTypeFont | ImageFont.ImageFont:
    if features.check("freetype2"):
        return ImageFont.load_default(size=size)
    return ImageFont.load_default_imagefont()


def fit_text(text: str, font: ImageFont.FreeTypeFont | ImageFont.ImageFont, width: float) -> str:
    """``text`` shortened to an ellipsis-ended prefix that fits in ``width`` pixels."""
    if font.getlength(text) <= width:
        return text
    lo, hi = 0, len(text)
    while lo < hi:  # the longest prefix that fits with the ellipsis
        mid = (lo + hi + 1) // 2
        if font.getlength(text[:mid] + "…") <= width:
            lo = mid
        else:
            hi = mid - 1
    return text[:lo] + "…"


def render_gif(
    layout: Layout,
    schedule: Schedule,
    path: str | Path,
    *,
    fps: int = 8,
    cell_px: int | None = None,
    start: int = 0,
    stop: int | None = None,
    every: int = 1,
    max_frames: int = 1000,
    title: str | None = None,
) -> Path:
    """Write an animated GIF of ``schedule`` on ``layout`` (see the module legend).

    Args:
        layout: The grid the episode ran on.
        schedule: The executed episode.
        path: Output file; must end in ``.gif``. Written atomically.
        fps: Frames per second of playback.
        cell_px: Pixels per cell; ``None`` picks one so the longer side of the grid
            is about 600 pixels.
        start: First time step drawn.
        stop: Last time step drawn (inclusive); ``None`` means ``schedule.horizon``.
        every: Draw every ``every``-th time step from ``start``.
        max_frames: Refuse to write more frames than this.
        title: Text shown first in the header strip.

    Returns:
        ``path`` as a :class:`~pathlib.Path`.

    Raises:
        ConfigError: An argument is out of range, the schedule does not fit the
            layout, or the GIF would have more than ``max_frames`` frames.
    """
    path = Path(path)
    if path.suffix.lower() != ".gif":
        raise ConfigError(f"path must end in .gif, got {str(path)!r}")
    fps = _check_int("fps", fps, 1)
    every = _check_int("every", every, 1)
    max_frames = _check_int("max_frames", max_frames, 1)
    if cell_px is None:
        cell_px = max(1, round(600 / max(layout.width, layout.height)))
    c = _check_int("cell_px", cell_px, 1)
    _check_schedule(layout, schedule)
    times = _frame_times(schedule.horizon, start, stop, every, max_frames)
    background = _background(layout, c, layout.width * c)
    frames = _frames(schedule, background, c, times, title)

    def write(fh: BinaryIO) -> None:
        first = next(frames)
        first.save(
            fh,
            format="GIF",
            save_all=True,
            append_images=frames,
            duration=round(1000 / fps),
            loop=0,
            optimize=False,
        )

    return atomic_write(path, write)


def _frame_times(horizon: int, start: int, stop: int | None, every: int, max_frames: int) -> range:
    """The time steps drawn; an out-of-range window or too many frames is an error."""
    start = _check_int("start", start, 0)
    if start > horizon:
        raise ConfigError(f"start must lie in [0, {horizon}] (the schedule horizon), got {start}")
    stop = horizon if stop is None else _check_int("stop", stop, 0)
    if not start <= stop <= horizon:
        raise ConfigError(f"stop must lie in [start={start}, horizon={horizon}], got {stop}")
    times = range(start, stop + 1, every)
    if len(times) > max_frames:
        raise ConfigError(
            f"the GIF would have {len(times)} frames, more than max_frames={max_frames}; "
            f"pass a larger every= (e.g. every={-(-len(times) // max_frames) * every}) "
            "or a smaller stop="
        )
    return times


def _frames(
    s: Schedule, background: Image.Image, c: int, times: range, title: str | None
) -> Iterator[Image.Image]:
    pos = np.asarray(s.positions, dtype=np.int64)
    tasks = np.asarray(s.tasks, dtype=np.int64).reshape(-1, 4)
    robot = np.asarray(s.task_robot, dtype=np.int64)
    arrival, assigned = np.asarray(s.task_arrival), np.asarray(s.task_assigned)
    pickup, delivered = np.asarray(s.task_pickup), np.asarray(s.task_delivered)
    header_font = _font(12)
    room = background.width - 8
    # Centred (anchored) text needs a FreeType font; without one robots go unlabelled.
    ids = c >= 14 and features.check("freetype2")
    id_font = ImageFont.load_default(size=max(8, int(c * 0.45))) if ids else None
    line_w, mark_w = max(1, c // 12), max(1, c // 8)
    colors = [_ROBOT0 + m % len(ROBOT_COLORS) for m in range(s.num_robots)]
    dark_text = [sum(robot_color(m)) > 450 for m in range(s.num_robots)]

    def centre(x: int, y: int) -> tuple[float, float]:
        return x * c + (c - 1) / 2, HEADER_PX + y * c + (c - 1) / 2

    def square(x: int, y: int, frac: float) -> tuple[float, float, float, float]:
        cx, cy, r = *centre(x, y), max(1.0, c * frac / 2)
        return cx - r, cy - r, cx + r, cy + r

    for t in times:
        img = background.copy()
        draw = ImageDraw.Draw(img)
        queued = np.flatnonzero((arrival <= t) & (t < assigned))
        going = np.flatnonzero((assigned <= t) & (t < pickup))
        carried = np.flatnonzero((pickup <= t) & (t < delivered))
        done = int(np.count_nonzero(delivered <= t))
        text = (
            f"t = {t} s   queued {len(queued)}   assigned {len(going)}   "
            f"carrying {len(carried)}   delivered {done}"
        )
        # The title ends in an ellipsis when too wide; the counters line starts with the
        # time, which every frame shows even on a tiny picture.
        lines = [fit_text(title, header_font, room), text] if title else [text]
        for row, line in enumerate(lines):
            draw.text((4, 3 + 15 * row), line, fill=_IDX["text"], font=header_font)
        for k in queued:
            draw.rectangle(square(*tasks[k, :2], 0.5), outline=_IDX["queued"], width=mark_w)
        for k in going:
            col = colors[robot[k]]
            draw.line([centre(*pos[t, robot[k]]), centre(*tasks[k, :2])], fill=col, width=line_w)
            draw.rectangle(square(*tasks[k, :2], 0.55), outline=col, width=mark_w + 1)
        for k in carried:
            x0, y0, x1, y1 = square(*tasks[k, 2:], 0.6)
            col = colors[robot[k]]
            draw.line([(x0, y0), (x1, y1)], fill=col, width=mark_w + 1)
            draw.line([(x0, y1), (x1, y0)], fill=col, width=mark_w + 1)
        for m in range(s.num_robots):
            draw.ellipse(square(*pos[t, m], 0.78), fill=colors[m])
        for k in carried:
            x, y = pos[t, robot[k]]
            side = max(2, round(c * 0.38))
            bx, by = x * c + c - side - max(0, c // 20), HEADER_PX + y * c + max(0, c // 20)
            draw.rectangle(
                (bx, by, bx + side - 1, by + side - 1), fill=_IDX["box"], outline=_IDX["box_edge"]
            )
        if id_font is not None:
            for m in range(s.num_robots):
                fill = _IDX["text"] if dark_text[m] else _IDX["white"]
                draw.text(centre(*pos[t, m]), str(m), fill=fill, font=id_font, anchor="mm")
        yield img
