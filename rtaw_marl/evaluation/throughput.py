"""Throughput of fixed-horizon episodes (``sim.episode_mode=horizon``): tasks finished.

LoRR's score, and a warehouse engineer's question: how many more tasks does a better
allocator finish in the same time, with traffic? One timestep is one second (LoRR's
convention), so tasks per robot-hour are ``finished / M / (T / 3600)``.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from rtaw_marl.evaluation.stats import mean_ci
from rtaw_marl.utils.renamed import upgrade_config

__all__ = ["LORR_PUBLISHED", "finished_diff", "throughput_markdown", "throughput_table"]

Results = Mapping[str, Mapping[str, Sequence[float]]]


def finished_diff(
    baseline: Sequence[float], other: Sequence[float], confidence: float = 0.95
) -> tuple[float, float | None]:
    """The paired gain in tasks finished of ``other`` over ``baseline``, in % of the
    baseline's mean (+ = more tasks), and the half-width of its t-interval."""
    base, oth = np.asarray(baseline, float), np.asarray(other, float)
    mean, half = mean_ci(oth - base, confidence)
    scale = 100.0 / base.mean()
    return mean * scale, None if half is None else half * scale


def _cell(diff: tuple[float, float | None]) -> str:
    pct, half = diff
    if half is None:
        return f"{pct:+.1f}% [n/a]"
    star = "*" if abs(pct) > half else ""
    return f"{pct:+.1f}% [{pct - half:+.1f}, {pct + half:+.1f}]{star}"


def throughput_table(
    results: Results,
    num_robots: int,
    horizon: int,
    baselines: Sequence[str] = ("mpdm",),
    confidence: float = 0.95,
) -> str:
    """A markdown table of tasks finished by the horizon, per policy, and a legend.

    Args:
        results: ``{policy: {metric: [per seed]}}`` as returned by ``evaluate``.
        num_robots: ``M``.
        horizon: ``T``, timesteps (seconds).
        baselines: Policies every other is compared with, where evaluated.
        confidence: Confidence level of the intervals.
    """
    bases = [b for i, b in enumerate(baselines) if b in results and b not in baselines[:i]]
    level = f"{100 * confidence:g}% CI"
    header = ["policy", f"tasks finished ± {level}", "tasks / robot-hour",
              f"mean wait ± {level}", "ms / timestep"]  # fmt: skip
    header += [f"finished vs {b}" for b in bases]
    rows = []
    for name, m in results.items():
        mean, half = mean_ci(m["tasks_finished"], confidence)
        wait, wait_half = mean_ci(m["wait_mean"], confidence)
        row = [
            name,
            f"{mean:,.0f}" + ("" if half is None else f" ± {half:,.0f}"),
            f"{mean / num_robots / (horizon / 3600):.1f}",
            f"{wait:.1f}" + ("" if wait_half is None else f" ± {wait_half:.1f}"),
            f"{1000 * np.mean(m['wall_time_s']) / horizon:.2f}",
        ]
        row += [
            "—" if b == name else _cell(finished_diff(results[b]["tasks_finished"],
                                                      m["tasks_finished"], confidence))
            for b in bases
        ]  # fmt: skip
        rows.append(row)
    n = min((len(m["tasks_finished"]) for m in results.values()), default=0)
    legend = (
        f"throughput over {horizon} timesteps, {num_robots} robots, {n} seed(s); finished vs X: "
        f"paired per seed, in % of X's mean (+ = more tasks); * = the {level} excludes 0"
    )
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(r) + " |" for r in rows]
    return "\n".join([*lines, legend])


#: LoRR 2024's published tasks finished on ``warehouse_large`` (5,000 timesteps), by
#: robots: (the start kit's default: greedy scheduler + PIBT-based planner, the best
#: entry). Another simulator and planner (headings and turns, its own traffic rules).
LORR_PUBLISHED: dict[int, tuple[int, int]] = {5000: (67_177, 94_232), 10_000: (63_924, 154_834)}


def throughput_markdown(runs: Sequence[tuple[str, Mapping]], reference: str = "mpdm") -> str:
    """One markdown table of several ``rtaw-eval`` results of horizon episodes.

    Args:
        runs: ``(setting label, results.json payload)`` pairs (a payload written
            before the simulator's keys were ``sim`` holds them as ``env``: read too).
        reference: The rule every policy is compared with.
    """
    lines = [
        "| setting | policy | seeds | tasks finished | tasks / robot-hour | vs MPDM "
        "| ms / timestep |",
        "|---|---|---:|---:|---:|---:|---:|",
    ]
    for label, payload in runs:
        sim = upgrade_config(payload["config"])["sim"]
        m, horizon = int(sim["num_robots"]), int(sim["horizon"])
        results = payload["policies"]
        for name, metrics in results.items():
            done = metrics["tasks_finished"]
            mean, half = mean_ci(done)
            versus = "—"
            if name != reference and reference in results:
                versus = _cell(finished_diff(results[reference]["tasks_finished"], done))
            lines.append(
                f"| {label} | {name} | {len(done)} | {mean:,.0f}"
                + ("" if half is None else f" ± {half:,.0f}")
                + f" | {mean / m / (horizon / 3600):.1f} | {versus} | "
                f"{1000 * np.mean(metrics['wall_time_s']) / horizon:.1f} |"
            )
        if m in LORR_PUBLISHED and "warehouse_large" in label:
            default, best = LORR_PUBLISHED[m]
            for who, value in (("LoRR 2024 default planner (published)", default),
                               ("LoRR 2024 best entry (published)", best)):  # fmt: skip
                lines.append(
                    f"| {label} | {who} | — | {value:,} | {value / m / (horizon / 3600):.1f} "
                    "| another planner | — |"
                )
    return "\n".join(lines)
