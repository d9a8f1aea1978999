"""LoRR's run-to-run spread and the own simulator's calibration against it.

Usage::

    python -m benchmarks.scripts.lorr_spread --own OWN.json OFFICIAL.json OFFICIAL2.json ...

Each ``OFFICIAL`` is an ``rtaw-lorr`` results file of the same problem and horizon (one
``lifelong`` run per scheduler: LoRR's simulator is deterministic only up to its
planner's timing, so repeated runs differ); ``OWN`` an ``rtaw-eval scenario=lorr``
results file (seeds). Prints per scheduler LoRR's runs, their mean and range, the own
mean with its 95% interval and its difference to LoRR's mean, then Kendall's tau over
the pairs of schedulers whose official means differ by more than the larger of their
two ranges (pairs within LoRR's own spread are not ranked by it).
"""

from __future__ import annotations

import argparse
import itertools
import json
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

from rtaw_marl.evaluation.report import markdown_table
from rtaw_marl.evaluation.stats import mean_ci
from rtaw_marl.policies.labels import upgrade_label


def resolved_tau(
    official: Mapping[str, Sequence[float]], own: Mapping[str, float]
) -> tuple[float, int, int]:
    """Kendall's tau between the official means and ``own`` over the pairs LoRR resolves
    (mean difference above the larger range); returns (tau, pairs used, pairs in all)."""
    names = [k for k in official if k in own]
    score, used = 0, 0
    for a, b in itertools.combinations(names, 2):
        spread = max(np.ptp(official[a]), np.ptp(official[b]))
        gap = float(np.mean(official[a]) - np.mean(official[b]))
        if abs(gap) <= spread:
            continue
        score += int(np.sign(gap) * np.sign(own[a] - own[b]))
        used += 1
    total = len(names) * (len(names) - 1) // 2
    return (score / used if used else float("nan")), used, total


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("official", nargs="+", type=Path)
    parser.add_argument("--own", type=Path, required=True)
    args = parser.parse_args()
    runs: dict[str, list[float]] = {}
    for path in args.official:
        for label, run in json.loads(path.read_text())["runs"].items():
            runs.setdefault(upgrade_label(label), []).append(float(run["tasks_finished"]))
    own_runs = json.loads(args.own.read_text())["policies"]
    own = {upgrade_label(k): v["tasks_finished"] for k, v in own_runs.items()}
    rows = []
    for label, got in runs.items():
        mean = float(np.mean(got))
        cells = [f"`{label}`", ", ".join(f"{v:,.0f}" for v in got), f"{mean:,.0f}",
                 f"{np.ptp(got):,.0f} ({100 * np.ptp(got) / mean:.1f}%)"]  # fmt: skip
        if label in own:
            m, half = mean_ci(own[label])
            ci = "" if half is None else f" ± {half:,.0f}"
            cells += [f"{m:,.0f}{ci}", f"{100 * (m - mean) / mean:+.1f}%"]
        else:
            cells += ["—", "—"]
        rows.append(cells)
    head = ["scheduler", "LoRR runs", "LoRR mean", "LoRR range", "own ± 95% CI", "own vs LoRR"]
    print(markdown_table(head, rows))
    tau, used, total = resolved_tau(runs, {k: float(np.mean(v)) for k, v in own.items()})
    print(f"\nKendall's tau over the {used} of {total} scheduler pairs LoRR resolves "
          f"(mean difference above both runs' range): {tau:+.2f}")  # fmt: skip


if __name__ == "__main__":
    main()
