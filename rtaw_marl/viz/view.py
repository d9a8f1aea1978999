"""The interactive episode viewer: one self-contained HTML file (``rtaw-view``).

The page holds its data and its code inline (no server, no network): open it in a
browser from the disk. It replays one executed episode, or two side by side on the
same map and clock (two policies on the same seed), side by side or stacked (whichever
gives the map larger cells), drawn on a canvas:

* robots coloured by state (idle, on the way to a pickup, carrying), with a legend;
* play, pause, speed, a timeline to scrub, zoom (wheel) and pan (drag);
* robots' headings, zoomed in, when they turn;
* click a robot: its task, its path from assignment to delivery and its waits; find a
  robot (``12``) or a task (``t34``, its stream id: the same task in both episodes) by
  id and follow it;
* a congestion heat map (waits per cell, per time bin) beside the map and optionally on
  it, per block of cells when cells are small, or the difference of the two episodes;
  and a chart of tasks delivered over time, smoothed over a window the user sets.

What the page reads is described in :mod:`rtaw_marl.viz.episode_data`. ``window.rtawView``
exposes the view's state and a few controls, which the browser tests drive.
"""

from __future__ import annotations

import html
import json
import re
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

from rtaw_marl.errors import ConfigError
from rtaw_marl.sim.layout import Layout
from rtaw_marl.sim.mapf.schedule import Schedule
from rtaw_marl.utils.atomic import atomic_write
from rtaw_marl.viz.episode_data import encode, episode_arrays, layout_cells, pack

__all__ = ["ViewEpisode", "file_size", "fill", "page", "write_view"]

MAX_EPISODES = 2
"""Episodes a page shows side by side."""

SCRIPTS = ("episode.js", "draw.js", "heat.js", "controls.js")
"""The page's code (``rtaw_marl/viz/viewer/``), inlined in this order: the episodes'
data, the drawing of maps and robots, the congestion and charts, the controls."""


@dataclass(frozen=True)
class ViewEpisode:
    """One episode to show.

    Attributes:
        name: Its label (the policy).
        schedule: The executed episode.
        summary: Numbers shown with it (``{"TTD": 1234.0}``).
        unfinished: Tasks robots still hold at the end that the schedule leaves out
            (:func:`rtaw_marl.viz.episode_data.open_tasks`), ``int32 [J, 10]``.
    """

    name: str
    schedule: Schedule
    summary: dict[str, Any] = field(default_factory=dict)
    unfinished: np.ndarray | None = None


def _asset(name: str) -> str:
    return resources.files("rtaw_marl.viz").joinpath("viewer", name).read_text(encoding="utf-8")


def page(
    layout: Layout,
    episodes: Sequence[ViewEpisode],
    title: str,
    progress: Callable[[str], None] | None = None,
) -> str:
    """The viewer's HTML for ``episodes`` (one or two) on ``layout``.

    Raises:
        ConfigError: No episode or more than :data:`MAX_EPISODES`, or episodes whose
            robot counts differ (side by side they share one map and one clock).
    """
    if not 1 <= len(episodes) <= MAX_EPISODES:
        raise ConfigError(f"the viewer shows 1 or {MAX_EPISODES} episodes, got {len(episodes)}")
    if len({ep.schedule.num_robots for ep in episodes}) > 1:
        raise ConfigError("episodes side by side must have the same number of robots")
    note = progress or (lambda _: None)
    packed = []
    for ep in episodes:
        note(f"packing {ep.name}: {ep.schedule.num_robots} robots, {ep.schedule.horizon} timesteps")
        arrays = episode_arrays(layout, ep.schedule, unfinished=ep.unfinished)
        packed.append(pack(arrays, ep.name, ep.summary))
    data = {
        "version": 1,
        "title": title,
        "width": layout.width,
        "height": layout.height,
        "cells": encode(layout_cells(layout)),
        "episodes": packed,
    }
    # "</" cannot end the inline script early once "<" is escaped (base64 has none).
    text = json.dumps(data, separators=(",", ":")).replace("<", "\\u003c")
    parts = {
        "TITLE": html.escape(title),
        "STYLE": _asset("viewer.css"),
        "SCRIPT": "\n".join(_asset(name) for name in SCRIPTS),
        "DATA": text,
    }
    return fill(_asset("page.html"), parts)


def fill(template: str, parts: dict[str, str]) -> str:
    """``template`` with each ``__KEY__`` replaced by ``parts[KEY]``, in one pass.

    One pass over the template only: a value is never searched again, so a title or a
    file name that reads ``__SCRIPT__`` stays text instead of pulling the viewer's code
    (or the data) into the page, as replacing the placeholders one after another did.

    Raises:
        KeyError: The template names a placeholder ``parts`` lacks (a bug of the page).
    """
    return _PLACEHOLDER.sub(lambda m: parts[m.group(1)], template)


#: The page's placeholders: ``__TITLE__``, ``__STYLE__``, ``__SCRIPT__``, ``__DATA__``.
_PLACEHOLDER = re.compile(r"__(TITLE|STYLE|SCRIPT|DATA)__")


def file_size(size: int) -> str:
    """``20.9 MB``, or ``48 kB`` below a tenth of a megabyte."""
    return f"{size / 1e6:.1f} MB" if size >= 100_000 else f"{size / 1e3:.0f} kB"


def write_view(
    path: str | Path,
    layout: Layout,
    episodes: Sequence[ViewEpisode],
    title: str,
    progress: Callable[[str], None] | None = None,
) -> Path:
    """:func:`page` written atomically to ``path`` (an ``.html`` file)."""
    text = page(layout, episodes, title, progress)
    if progress is not None:
        progress(f"writing {path} ({file_size(len(text.encode('utf-8')))})")
    return atomic_write(path, lambda fh: fh.write(text.encode("utf-8")))
