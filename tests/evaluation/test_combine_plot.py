"""The combined plot's data, read from its spec and from the matplotlib figure (never
its pixels): lines over a numeric swept key, bars over another, one column of panels per
value of the other keys, one row of paired differences per baseline, and the title."""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import pytest

from rtaw_marl.errors import ConfigError
from rtaw_marl.evaluation.combine import Combined, combine, load_jobs
from rtaw_marl.evaluation.combine_plot import VALUES, plot_figure, plot_spec, seeds_text
from rtaw_marl.evaluation.stats import mean_ci

pytestmark = pytest.mark.unit

SEEDS = [0, 1, 2]
POLICIES = ("mpdm", "lookahead")
LAYOUTS = {"A": 0.0, "C": 1000.0}


def _ttd(robots: int, layout: str, policy: int, seed: int) -> float:
    """Made-up TTDs: every setting, policy and seed its own number; the second policy
    below the first by a seed-dependent amount (paired intervals with some width)."""
    return 10_000.0 / robots + LAYOUTS[layout] + 7.0 * seed - policy * (50.0 + seed)


def _sweep(root: Path, robots: Sequence[int], layouts: Sequence[str] = ("A",)) -> Path:
    """One job folder per robot count and layout, numbered in that order, each with a
    results.json and the overrides Hydra writes."""
    for i, (r, layout) in enumerate((r, lay) for r in robots for lay in layouts):
        job = root / str(i)
        (job / ".hydra").mkdir(parents=True)
        overrides = [f"sim.num_robots={r}", *([f"layout={layout}"] if len(layouts) > 1 else [])]
        overrides += ["sim.num_tasks=20", "seeds=[0,1,2]", "policy=[mpdm,lookahead]"]
        (job / ".hydra" / "overrides.yaml").write_text("".join(f"- {o}\n" for o in overrides))
        policies = {
            name: {
                "ttd": [_ttd(r, layout, p, s) for s in SEEDS],
                "tasks_finished": [20 + p * s for s in SEEDS],
            }
            for p, name in enumerate(POLICIES)
        }
        config = {"sim": {"num_robots": r, "num_tasks": 20, "episode_mode": "drain",
                          "horizon": None},
                  "layout": {"name": layout}, "navigator": {"name": "astar"},
                  "policy": list(POLICIES), "seeds": SEEDS}  # fmt: skip
        payload = {"config": config, "seeds": SEEDS, "policies": policies}
        (job / "results.json").write_text(json.dumps(payload))
    return root


def _combined(root: Path, **options: str) -> Combined:
    return combine(load_jobs([root]), **options)


def test_a_numeric_sweep_is_lines_over_the_keys_values(tmp_path: Path) -> None:
    """Jobs 20, 5, 10 robots: one line per policy over x = 5, 10, 20 (sorted by value),
    its points the means of the files' values, a band each; below, the paired
    difference with MPDM, MPDM itself the dashed line at 0."""
    combined = _combined(_sweep(tmp_path, [20, 5, 10]))
    spec = plot_spec(combined)
    assert (spec.x_key, spec.numeric, spec.ncols) == ("sim.num_robots", True, 1)
    assert [p.row for p in spec.panels] == [VALUES, "mpdm"]
    means, diffs = spec.panels
    assert [s.policy for s in means.series] == ["mpdm", "lookahead"]
    for p, series in enumerate(means.series):
        assert series.x == [5.0, 10.0, 20.0]
        expected = [mean_ci([_ttd(r, "A", p, s) for s in SEEDS]) for r in (5, 10, 20)]
        assert series.y == pytest.approx([m for m, _ in expected])
        assert series.high == pytest.approx([m + h for m, h in expected])
    (vs,) = diffs.series  # mpdm is not compared with itself
    per_seed = [(50.0 + s) for s in SEEDS]  # mpdm - lookahead on every seed
    assert vs.y == pytest.approx([100 * np.mean(per_seed) / np.mean(
        [_ttd(r, "A", 0, s) for s in SEEDS]) for r in (5, 10, 20)])  # fmt: skip
    fig = plot_figure(spec)
    top, bottom = fig.axes
    lines = [ln for ln in top.get_lines() if ln.get_label() in POLICIES]
    assert [ln.get_label() for ln in lines] == ["mpdm", "lookahead"]
    assert list(lines[1].get_xdata()) == [5.0, 10.0, 20.0]
    assert list(lines[1].get_ydata()) == pytest.approx(means.series[1].y)
    assert len(top.collections) == 2  # one interval band per policy
    assert not top.patches  # no bars
    zero = [ln for ln in bottom.get_lines() if ln.get_label() == "mpdm (baseline)"]
    assert len(zero) == 1
    assert list(zero[0].get_ydata()) == [0.0, 0.0]
    # 5, 10, 20 double at each step: a log axis spaces them evenly; 10-40 a linear one.
    assert top.get_xscale() == "log"
    evenly = plot_spec(_combined(_sweep(tmp_path / "linear", [10, 20, 30, 40])))
    assert (evenly.numeric, evenly.log_x) == (True, False)
    assert plot_figure(evenly).axes[0].get_xscale() == "linear"


def test_two_swept_keys_are_facets(tmp_path: Path) -> None:
    """Robots (numeric) on x, one column per layout; ``--x layout`` turns it round:
    bars over the layouts, one column per robot count."""
    root = _sweep(tmp_path, [5, 10, 20, 40], ["A", "C"])
    combined = _combined(root, compare_to="lookahead")
    spec = plot_spec(combined)
    assert (spec.x_key, spec.numeric, spec.log_x, spec.ncols) == ("sim.num_robots", True, True, 2)
    assert [(p.row, p.facet) for p in spec.panels] == [
        (VALUES, {"layout": "A"}), (VALUES, {"layout": "C"}),
        ("mpdm", {"layout": "A"}), ("mpdm", {"layout": "C"}),
        ("lookahead", {"layout": "A"}), ("lookahead", {"layout": "C"}),
    ]  # fmt: skip
    c_means = spec.panels[1].series[0]
    assert c_means.y == pytest.approx([np.mean([_ttd(r, "C", 0, s) for s in SEEDS])
                                       for r in (5, 10, 20, 40)])  # fmt: skip
    assert [s.policy for s in spec.panels[4].series] == ["mpdm"]  # against lookahead
    assert spec.panels[4].ylabel == "TTD vs LOOKAHEAD (%, + = better)"
    fig = plot_figure(spec)
    assert len(fig.axes) == 6
    assert [ax.get_title() for ax in fig.axes[:2]] == ["layout=A", "layout=C"]
    assert fig.axes[0].get_xscale() == "log"
    assert [ax.get_xlabel() for ax in fig.axes[4:]] == ["sim.num_robots"] * 2

    turned = plot_spec(combined, x="layout")
    assert (turned.x_key, turned.numeric, turned.ncols) == ("layout", False, 4)
    assert turned.panels[0].facet == {"sim.num_robots": "5"}
    assert turned.panels[0].series[0].x == ["A", "C"]
    bars = plot_figure(turned).axes[0]
    assert len(bars.patches) == 4  # two policies x two layouts
    assert sorted(p.get_height() for p in bars.patches) == pytest.approx(
        sorted(y for s in turned.panels[0].series for y in s.y)
    )


def test_a_categorical_sweep_is_bars(tmp_path: Path) -> None:
    """Bars over the layouts; lookahead's bars stand at the same places in the row of
    differences (where MPDM has none) as in the row of means."""
    spec = plot_spec(_combined(_sweep(tmp_path, [5], ["A", "C"])))
    assert (spec.x_key, spec.numeric, spec.ncols) == ("layout", False, 1)
    assert spec.categories == ["A", "C"]
    assert spec.panels[0].series[0].x == ["A", "C"]
    means, diffs = plot_figure(spec).axes
    assert [t.get_text() for t in diffs.get_xticklabels()] == ["A", "C"]
    assert len(means.patches) == 4
    assert len(diffs.patches) == 2
    placed = sorted(p.get_x() for p in means.patches)
    assert sorted(p.get_x() for p in diffs.patches) == placed[1::2]


def test_the_title_names_the_fixed_setting_and_the_seeds(tmp_path: Path) -> None:
    combined = _combined(_sweep(tmp_path, [5, 10], ["A", "C"]), metric="tasks_finished")
    spec = plot_spec(combined)
    assert spec.title == (
        "tasks_finished: navigator=astar, sim.num_tasks=20, sim.episode_mode=drain\n"
        "seeds 0-2, n=3; 95% t-intervals"
    )
    assert plot_figure(spec).get_suptitle() == spec.title
    # More tasks finished is better: lookahead's (20, 21, 22) over mpdm's (20, 20, 20).
    assert spec.panels[2].series[0].y == pytest.approx([5.0, 5.0])
    assert spec.panels[2].ylabel == "tasks_finished vs MPDM (%, + = better)"


@pytest.mark.parametrize(
    ("seeds", "text"),
    [(range(20), "seeds 0-19, n=20"), ([0, 1], "seeds 0, 1, n=2"),
     ([0, 1, 2, 7, 9, 10, 11], "seeds 0-2, 7, 9-11, n=7"), ([3], "seed 3, n=1")],
)  # fmt: skip
def test_seeds_text(tmp_path: Path, seeds: Sequence[int], text: str) -> None:
    (tmp_path / "results.json").write_text(json.dumps({
        "config": {}, "seeds": list(seeds), "policies": {"mpdm": {"ttd": [1.0] * len(seeds)}}
    }))  # fmt: skip
    assert seeds_text(_combined(tmp_path).rows) == text


def test_an_x_that_is_not_swept_is_refused(tmp_path: Path) -> None:
    combined = _combined(_sweep(tmp_path, [5, 10]))
    with pytest.raises(
        ConfigError, match=r"^--x layout is not a swept key; swept: sim.num_robots$"
    ):
        plot_spec(combined, x="layout")
