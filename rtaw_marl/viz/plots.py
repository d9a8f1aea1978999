"""Plots of training runs: the greedy evaluations over frames and over wall time, the
imitation warm start's rounds first, with the rules as bands to clear."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from rtaw_marl.evaluation.stats import mean_ci

__all__ = ["curve_series", "plot_training_curve"]

#: Colours of the network and of the rules' bands.
NETWORK, MPDM, BEST = "tab:blue", "tab:red", "tab:green"


def curve_series(
    history: Sequence[Mapping[str, float]],
    imitation: Sequence[Mapping[str, float]] = (),
    metric: str = "ttd",
) -> dict[str, list[float]]:
    """The curve's points: the warm start's rounds, then PPO's evaluations.

    Frames count the warm start's labelled decisions first and PPO's after them, so one
    axis holds both phases.

    Args:
        history: The evaluations' rows (``frames``, ``wall_s``, ``ttd`` ...).
        imitation: The warm start's rows (``decisions``, ``wall_s``, ``ttd`` ...); rows
            without the metric (older runs) are left out.
        metric: ``ttd`` or ``tasks_finished``.

    Returns:
        ``frames``, ``wall_s`` and ``value`` per point, and ``imitation_frames`` (one
        value: where PPO starts on the frames axis) and ``imitation_points`` (how many of
        the points are the warm start's).
    """
    rounds = [row for row in imitation if metric in row]
    shift = float(rounds[-1]["decisions"]) if rounds else 0.0
    rows = [(float(r["decisions"]), r) for r in rounds]
    rows += [(shift + float(r["frames"]), r) for r in history if metric in r]
    return {
        "frames": [x for x, _ in rows],
        "wall_s": [float(r.get("wall_s", float("nan"))) for _, r in rows],
        "value": [float(r[metric]) for _, r in rows],
        "imitation_frames": [shift],
        "imitation_points": [float(len(rounds))],
    }


def plot_training_curve(
    history: Sequence[Mapping[str, float]],
    path: Path,
    *,
    rules: Mapping[str, Sequence[float]] | None = None,
    rule: str | None = None,
    metric: str = "ttd",
    imitation: Sequence[Mapping[str, float]] = (),
) -> Path | None:
    """The run's curve: the greedy network's mean ``metric`` on the selection seeds over
    frames (left) and wall time (right), the warm start shaded, MPDM and the best rule
    as bands (their means with 95% intervals over the same seeds).

    Args:
        history: The evaluations' rows.
        path: Where the PNG goes.
        rules: Rule -> its ``metric`` per selection seed; ``None``: the rows' rule means
            (``mpdm_ttd``, ``lookahead_ttd``; older runs) drawn as lines.
        rule: The best rule (the bar), one of ``rules``.
        metric: ``ttd`` or ``tasks_finished``.
        imitation: The warm start's rows.

    Returns:
        The PNG path, or ``None`` when there is nothing to plot.
    """
    series = curve_series(history, imitation, metric)
    if not series["value"]:
        return None
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(10, 3.8), dpi=120, sharey=True)
    start = series["imitation_frames"][0]
    warm = int(series["imitation_points"][0])
    minutes = max(series["wall_s"]) > 120.0
    unit = 60.0 if minutes else 1.0
    wall = [s / unit for s in series["wall_s"]]
    for ax, x in zip(axes, (series["frames"], wall), strict=True):
        ax.plot(x, series["value"], marker="o", color=NETWORK, label="network (greedy)")
        if warm:
            ax.plot(x[:warm], series["value"][:warm], marker="s", linestyle="",
                    color="tab:purple", label="after an imitation round")  # fmt: skip
        _bands(ax, history, rules, rule, metric)
        ax.grid(alpha=0.3)
    if warm:
        axes[0].axvspan(0, start, color="tab:purple", alpha=0.08, label="imitation")
        axes[1].axvspan(0, wall[warm - 1], color="tab:purple", alpha=0.08)
    axes[0].set_xlabel("frames: imitation's labelled decisions, then PPO's")
    axes[1].set_xlabel(f"wall time since the start ({'min' if minutes else 's'})")
    label = "mean episode TTD (lower is better)" if metric == "ttd" else "tasks finished"
    axes[0].set_ylabel(label)
    axes[0].legend(fontsize=7, loc="best")
    fig.suptitle("Greedy evaluations on the selection seeds, the rules' 95% intervals")
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path)
    plt.close(fig)
    return path


def _bands(
    ax: Any,
    history: Sequence[Mapping[str, float]],
    rules: Mapping[str, Sequence[float]] | None,
    rule: str | None,
    metric: str,
) -> None:
    """MPDM and the best rule: a band each (``rules`` given), else the rows' lines."""
    if rules is None:
        first = history[0]
        ax.axhline(first[f"mpdm_{metric}"], color=MPDM, linestyle="--", label="MPDM")
        for name in ("lookahead", "pair_greedy"):  # the bar of older runs, if logged
            if f"{name}_{metric}" in first:
                ax.axhline(first[f"{name}_{metric}"], color=BEST, linestyle=":", label=name)
        return
    shown = ["mpdm"] + ([rule] if rule and rule != "mpdm" else [])
    for name, colour in zip(shown, (MPDM, BEST), strict=False):
        mean, half = mean_ci(rules[name])
        label = "MPDM" if name == "mpdm" else f"{name} (the best rule)"
        ax.axhline(mean, color=colour, linestyle="--", linewidth=1, label=label)
        if half is not None:
            ax.axhspan(mean - half, mean + half, color=colour, alpha=0.12)
