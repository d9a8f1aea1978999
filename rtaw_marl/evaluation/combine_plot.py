"""The plot of a combined sweep (:mod:`rtaw_marl.evaluation.combine`): its series, then
the figure.

:func:`plot_spec` says what is drawn, as plain data (tests read it, not pixels);
:func:`plot_figure` draws it with matplotlib's Agg canvas, :func:`plot_png` as PNG bytes.

- **x axis**: a swept key (``--x``; by default the first swept key whose every value is
  a number, else the first swept key). A numeric key is drawn as lines (x = the key's
  value, one line per policy) with the 95% interval as a band; any other key as
  grouped bars with the interval as error bars.
- **facets**: one column of panels per value of the other swept keys (robots as x,
  layout as facet).
- **rows**: the metric's mean with its interval; below it, one row per baseline
  (``--reference``, then ``--compare-to``) with every other policy's paired difference
  in percent of the baseline's mean and its interval (``+`` = better, or more for a
  metric with no better side), the baseline itself the line at 0.
- **title**: the metric, what every job shares (:attr:`Combined.fixed`) and the seeds
  (``seeds 0-19, n=20``).
"""

from __future__ import annotations

import io
import math
import textwrap
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from rtaw_marl.errors import ConfigError
from rtaw_marl.evaluation.combine import Combined, Row
from rtaw_marl.evaluation.metric_goals import difference_wording, metric_label
from rtaw_marl.evaluation.report import baseline_label
from rtaw_marl.evaluation.stats import mean_ci
from rtaw_marl.sim.inputs import seed_span

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

__all__ = ["Panel", "PlotSpec", "Series", "plot_figure", "plot_png", "plot_spec", "seeds_text"]

#: Where the panels' values come from: the metric's means, or a baseline's differences.
VALUES = "values"

#: The most numeric x values that each get a labelled tick.
MAX_TICKS = 12

#: A row's point in a panel: ``(y, low, high)``, or ``None`` where it has none there.
_Point = tuple[float, float | None, float | None]
_Points = Callable[[Row], _Point | None]


@dataclass(frozen=True)
class Series:
    """One policy's points in one panel.

    Attributes:
        policy: The policy (its colour is the same in every panel).
        x: The x values: numbers on a numeric axis, else category labels.
        y: The means (or paired differences in %), one per x.
        low: The intervals' lower ends (``None``: no interval, one seed).
        high: Their upper ends.
    """

    policy: str
    x: list[float | str]
    y: list[float]
    low: list[float | None]
    high: list[float | None]


@dataclass(frozen=True)
class Panel:
    """One subplot.

    Attributes:
        row: :data:`VALUES`, or the baseline the differences are taken against.
        facet: The other swept keys' values of this column (``{}``: one column).
        ylabel: The y axis's label.
        series: One per policy drawn here.
    """

    row: str
    facet: dict[str, str]
    ylabel: str
    series: list[Series]


@dataclass(frozen=True)
class PlotSpec:
    """What the combined plot draws.

    Attributes:
        title: The figure's title (metric, what is fixed, seeds).
        x_key: The swept key on the x axis (``None``: nothing swept, one bar group).
        numeric: Whether x is numeric (lines and bands) or categorical (bars).
        log_x: Whether the numeric x axis is logarithmic (:func:`_log_scale`).
        categories: The categorical x axis's labels, in every panel the same (``[]``
            when x is numeric).
        policies: Every policy, in colour order (and bar order).
        panels: Row by row (values, then each baseline), facet by facet.
        ncols: Panels per row (the number of facets).
    """

    title: str
    x_key: str | None
    numeric: bool
    log_x: bool
    categories: list[str]
    policies: list[str]
    panels: list[Panel]
    ncols: int


def _is_number(text: str) -> bool:
    try:
        return math.isfinite(float(text))
    except ValueError:
        return False


def _x_key(combined: Combined, x: str | None) -> str | None:
    """The x axis's key: ``x`` if swept, else the first numeric swept key, else the first.

    Raises:
        ConfigError: ``x`` is not a swept key.
    """
    if x is not None:
        if x not in combined.swept:
            swept = ", ".join(combined.swept) or "none (one setting)"
            raise ConfigError(f"--x {x} is not a swept key; swept: {swept}")
        return x
    numeric = [k for k in combined.swept if all(_is_number(r.setting[k]) for r in combined.rows)]
    return (numeric or combined.swept or [None])[0]


def seeds_text(rows: Sequence[Row]) -> str:
    """``seeds 0-19, n=20`` (runs of three or more consecutive seeds joined), or ``seeds
    differ by setting, n=5-20``."""
    distinct = {tuple(row.seeds) for row in rows}
    if len(distinct) > 1:
        counts = sorted({len(s) for s in distinct})
        span = f"{counts[0]}-{counts[-1]}" if len(counts) > 1 else f"{counts[0]}"
        return f"seeds differ by setting, n={span}"
    seeds = distinct.pop()
    return f"seed{'s' if len(seeds) > 1 else ''} {seed_span(seeds)}, n={len(seeds)}"


def _title(combined: Combined, confidence: float) -> str:
    """The metric and what every job shares; below, the seeds and the intervals."""
    fixed = ", ".join(f"{k}={v}" for k, v in combined.fixed.items())
    head = metric_label(combined.metric) + (f": {fixed}" if fixed else "")
    return f"{head}\n{seeds_text(combined.rows)}; {100 * confidence:g}% t-intervals"


def _mean_point(confidence: float) -> _Points:
    def point(row: Row) -> _Point:
        mean, half = mean_ci(row.values, confidence)
        return (mean, None, None) if half is None else (mean, mean - half, mean + half)

    return point


def _diff_point(base: str) -> _Points:
    def point(row: Row) -> _Point | None:
        diff = row.vs.get(base)
        if diff is None or diff.pct is None:
            return None
        return diff.pct, diff.pct_low, diff.pct_high

    return point


def _series(
    policy: str, rows: Sequence[Row], x_key: str | None, numeric: bool, points: _Points
) -> Series | None:
    """``policy``'s points over ``rows`` (one facet), sorted by x when numeric."""
    keyed: list[tuple[float | str, _Point]] = []
    for row in rows:
        point = points(row) if row.policy == policy else None
        if point is not None:
            x = "all" if x_key is None else row.setting[x_key]
            keyed.append((float(x) if numeric else x, point))
    if not keyed:
        return None
    if numeric:
        keyed.sort(key=lambda item: float(item[0]))
    return Series(
        policy,
        [x for x, _ in keyed],
        [p[0] for _, p in keyed],
        [p[1] for _, p in keyed],
        [p[2] for _, p in keyed],
    )


def plot_spec(combined: Combined, confidence: float = 0.95, x: str | None = None) -> PlotSpec:
    """What :func:`plot_figure` draws for ``combined`` (see the module's docstring).

    Args:
        combined: The combined sweep.
        confidence: The intervals' confidence level (the title's).
        x: The swept key on the x axis; by default the first numeric one, else the first.

    Raises:
        ConfigError: ``x`` is not a swept key.
    """
    x_key = _x_key(combined, x)
    numeric = x_key is not None and all(_is_number(r.setting[x_key]) for r in combined.rows)
    others = [k for k in combined.swept if k != x_key]
    facets = list({tuple(r.setting[k] for k in others): None for r in combined.rows})
    policies = list(dict.fromkeys(r.policy for r in combined.rows))
    label = metric_label(combined.metric)
    rows: list[tuple[str, str, _Points]] = [
        (VALUES, f"{label} (mean, {100 * confidence:g}% interval)", _mean_point(confidence))
    ]
    sign = difference_wording(combined.metric)[1]
    for base in combined.baselines:
        rows.append((base, f"{label} vs {baseline_label(base)} (%, {sign})", _diff_point(base)))
    panels = []
    for row, ylabel, points in rows:
        for facet in facets:
            mine = [r for r in combined.rows if tuple(r.setting[k] for k in others) == facet]
            found = [_series(p, mine, x_key, numeric, points) for p in policies]
            series = [s for s in found if s is not None]
            panels.append(Panel(row, dict(zip(others, facet, strict=True)), ylabel, series))
    title = _title(combined, confidence)
    xs = ["all" if x_key is None else r.setting[x_key] for r in combined.rows]
    log_x = numeric and _log_scale([float(x) for x in xs])
    categories = [] if numeric else list(dict.fromkeys(xs))
    return PlotSpec(title, x_key, numeric, log_x, categories, policies, panels, len(facets))


def _log_scale(values: Sequence[float]) -> bool:
    """Whether x values are spaced more evenly on a log axis than on a linear one
    (``5, 10, 20, 40`` are; ``10, 20, 30, 40`` are not): all positive, at least three,
    spanning a factor of 4 or more."""
    xs = np.unique(np.asarray(values, dtype=float))
    if xs.size < 3 or xs[0] <= 0 or xs[-1] / xs[0] < 4:
        return False

    def unevenness(points: np.ndarray) -> float:
        gaps = np.diff(points)
        return float(gaps.std() / gaps.mean())

    return unevenness(np.log(xs)) < unevenness(xs)


def plot_figure(spec: PlotSpec) -> Figure:
    """The figure of ``spec`` on matplotlib's Agg canvas (no pyplot state)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg  # the cli extra
    from matplotlib.figure import Figure

    nrows = len(spec.panels) // spec.ncols
    width = max(6.0, 4.2 * spec.ncols)
    fig = Figure(figsize=(width, 1.0 + 3.0 * nrows), layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(nrows, spec.ncols, squeeze=False, sharex="col", sharey="row")
    colours = {policy: f"C{i}" for i, policy in enumerate(spec.policies)}
    for i, panel in enumerate(spec.panels):
        ax = axes[i // spec.ncols][i % spec.ncols]
        if spec.numeric:
            if spec.log_x:
                ax.set_xscale("log")
            _draw_lines(ax, panel, colours)
        else:
            _draw_bars(ax, panel, spec.categories, list(colours))
        if panel.row != VALUES:
            ax.axhline(0.0, color=colours[panel.row], linestyle="--", linewidth=1.0,
                       label=f"{panel.row} (baseline)")  # fmt: skip
        if i % spec.ncols == 0:
            ax.set_ylabel(panel.ylabel, fontsize=8)
        if i < spec.ncols and panel.facet:
            ax.set_title(", ".join(f"{k}={v}" for k, v in panel.facet.items()), fontsize=9)
        if i >= len(spec.panels) - spec.ncols and spec.x_key is not None:
            ax.set_xlabel(spec.x_key)
        ax.tick_params(labelsize=8)
        ax.grid(alpha=0.3)
    handles = [h for ax in axes.flat for h in ax.get_legend_handles_labels()[0]]
    labels = [lb for ax in axes.flat for lb in ax.get_legend_handles_labels()[1]]
    unique = dict(zip(labels, handles, strict=True))
    fig.legend(unique.values(), unique.keys(), loc="outside lower center",
               ncols=min(len(unique), 6), fontsize=8)  # fmt: skip
    wrap = max(60, int(width * 13))
    lines = spec.title.split("\n")
    fig.suptitle("\n".join(textwrap.fill(line, wrap) for line in lines), fontsize=10)
    return fig


def _draw_lines(ax: Axes, panel: Panel, colours: dict[str, str]) -> None:
    """One line per series (x numeric) with its interval as a band where it has one."""
    xs: set[float] = set()
    for s in panel.series:
        x = [float(v) for v in s.x]
        xs.update(x)
        ax.plot(x, s.y, marker="o", markersize=3, color=colours[s.policy], label=s.policy)
        low = [v for v in s.low if v is not None]
        high = [v for v in s.high if v is not None]
        if len(low) == len(high) == len(x):  # no band where a point has no interval
            ax.fill_between(x, low, high, color=colours[s.policy], alpha=0.2, linewidth=0)
    if 0 < len(xs) <= MAX_TICKS:  # each value a tick; more: matplotlib's own ticks
        ax.set_xticks(sorted(xs), [f"{v:g}" for v in sorted(xs)])
        ax.minorticks_off()


def _draw_bars(ax: Axes, panel: Panel, categories: list[str], policies: list[str]) -> None:
    """Grouped bars (x categorical), the intervals as error bars; a policy's bar has
    its place in every panel, so the rows line up."""
    step = 0.8 / len(policies)
    for s in panel.series:
        i = policies.index(s.policy)
        at = np.array([categories.index(str(x)) for x in s.x], dtype=float) - 0.4 + step * (i + 0.5)
        y = np.array(s.y)
        low = np.array([m if v is None else v for m, v in zip(s.y, s.low, strict=True)])
        high = np.array([m if v is None else v for m, v in zip(s.y, s.high, strict=True)])
        ax.bar(at, y, step, yerr=[y - low, high - y], capsize=2, color=f"C{i}",
               label=s.policy)  # fmt: skip
    ax.set_xticks(range(len(categories)), categories)


def plot_png(combined: Combined, confidence: float = 0.95, x: str | None = None) -> bytes:
    """The combined plot as PNG bytes (:func:`plot_spec`, :func:`plot_figure`).

    Raises:
        ConfigError: ``x`` is not a swept key.
    """
    buffer = io.BytesIO()
    plot_figure(plot_spec(combined, confidence, x)).savefig(buffer, format="png", dpi=110)
    return buffer.getvalue()
