"""The judge's table: schedulers in LoRR's own simulator beside the project's PIBT one.

Rows are schedulers; the official columns come from ``rtaw-lorr`` results (one
``lifelong`` run each: LoRR's problem is fixed, its simulator deterministic up to the
planner's timing), the own columns from ``rtaw-eval`` results of the same problem and
horizon (``scenario=lorr sim.horizon=T``, several seeds: the mean and its 95% interval).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from rtaw_marl.evaluation.stats import mean_ci
from rtaw_marl.integrations.lorr.config import LORR_DEFAULT
from rtaw_marl.policies.labels import upgrade_label

__all__ = ["judge_markdown", "rank_agreement"]


def _ranks(values: Mapping[str, float]) -> dict[str, int]:
    order = sorted(values, key=lambda k: -values[k])
    return {k: i + 1 for i, k in enumerate(order)}


def rank_agreement(official: Mapping[str, float], own: Mapping[str, float]) -> float:
    """Kendall's tau between two rankings of the schedulers both have (1: the same
    order, -1: reversed); NaN with fewer than two."""
    common = [k for k in official if k in own]
    pairs, score = 0, 0
    for i, a in enumerate(common):
        for b in common[i + 1 :]:
            s = np.sign(official[a] - official[b]) * np.sign(own[a] - own[b])
            score += int(s)
            pairs += 1
    return score / pairs if pairs else float("nan")


def judge_markdown(
    official: Mapping[str, Any], own: Mapping[str, Any] | None = None, base: str = "mpdm"
) -> str:
    """A markdown table of one problem and horizon, and a line on the rankings.

    Args:
        official: An ``rtaw-lorr`` results object.
        own: An ``rtaw-eval`` results object of the same problem and horizon, or ``None``.
        base: The scheduler the gains are measured against (in both simulators).
    """
    # rtaw-lorr files written before labels were short say "rtaw:generalist_plus@k32"
    # (rtaw-eval's are upgraded by their reader): matched, and shown, by today's label.
    runs = {upgrade_label(k): v for k, v in official["runs"].items()}
    steps = int(official["config"]["timesteps"])
    got = {k: float(v["tasks_finished"]) for k, v in runs.items()}
    own_runs = (own or {}).get("policies", {})
    own_mean = {k: float(np.mean(v["tasks_finished"])) for k, v in own_runs.items()}
    header = [
        "scheduler", "LoRR: tasks finished", f"vs {LORR_DEFAULT}", f"vs {base}", "timeouts",
        "deferred", "scheduler ms / timestep", "own PIBT: tasks finished ± 95% CI",
        f"own vs {base}", "rank LoRR / own",
    ]  # fmt: skip
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    ranks, own_ranks = _ranks(got), _ranks(own_mean)
    for label, run in runs.items():
        sched = run.get("scheduler") or {}
        calls = max(1, int(sched.get("calls", 0) or 1))
        ms = f"{1000.0 * float(sched['seconds']) / calls:.1f}" if sched else "(C++)"
        cells = [
            f"`{label}`",
            f"{run['tasks_finished']:,}",
            _gain(got, label, LORR_DEFAULT),
            _gain(got, label, base),
            str(run["timeouts"]),
            f"{int(sched['deferred']):,}" if sched else "n/a",
            ms,
            _own(own_runs.get(label)),
            _own_gain(own_runs, label, base),
            f"{ranks[label]} / {own_ranks.get(label, '—')}",
        ]
        lines.append("| " + " | ".join(cells) + " |")
    tau = rank_agreement({k: got[k] for k in own_mean if k in got}, own_mean)
    seeds = len((own or {}).get("seeds", []))
    lines += [
        "",
        f"{steps} timesteps, `planTimeLimit` {official['config']['plan_time_ms']} ms; "
        f"own simulator: seeds {(seeds and f'0-{seeds - 1}') or '—'}. Schedule errors: "
        f"{sum(int(r['schedule_errors']) for r in runs.values())}, planner errors: "
        f"{sum(int(r['planner_errors']) for r in runs.values())}. Rank agreement (Kendall's "
        f"tau over the schedulers in both): {tau:+.2f}.",
    ]
    return "\n".join(lines)


def _gain(values: Mapping[str, float], label: str, base: str) -> str:
    if base not in values or label == base or not values[base]:
        return "—"
    return f"{100.0 * (values[label] / values[base] - 1):+.1f}%"


def _own(entry: Mapping[str, Sequence[float]] | None) -> str:
    if entry is None:
        return "—"
    mean, half = mean_ci(np.asarray(entry["tasks_finished"], float))
    return f"{mean:,.0f}" + ("" if half is None else f" ± {half:,.0f}")


def _own_gain(runs: Mapping[str, Any], label: str, base: str) -> str:
    if label not in runs or base not in runs or label == base:
        return "—"
    a = np.asarray(runs[base]["tasks_finished"], float)
    b = np.asarray(runs[label]["tasks_finished"], float)
    mean, half = mean_ci(b - a)
    scale = 100.0 / a.mean()
    if half is None:
        return f"{mean * scale:+.1f}%"
    star = "*" if abs(mean) > half else ""
    return (
        f"{mean * scale:+.1f}% [{(mean - half) * scale:+.1f}, {(mean + half) * scale:+.1f}]{star}"
    )
