"""The Table I figure (docs/img/table1_ttd.png) from the stored per-seed TTDs.

Reads ``benchmarks/data/table1_paper.json`` (written by ``python -m benchmarks.run table1_paper
write=true``) and draws, per row, every policy's paired TTD gain over MPDM in percent
with its 95% interval (the same paired t-intervals as the tables; positive = lower TTD
than MPDM), so the figure always shows the table it sits under.

    python -m benchmarks.scripts.table1_plot [--data benchmarks/data/table1_paper.json] \
        [--output docs/img/table1_ttd.png]
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from rtaw_marl.evaluation.stats import paired_difference
from rtaw_marl.utils.atomic import atomic_write

REFERENCE = "MPDM"
COLORS = {
    "RBTS": "#9e9e9e",
    "hungarian": "#bcbd22",
    "lookahead": "#1f77b4",
    "RTAW": "#ff7f0e",
    "RTAW+": "#d62728",
    "hindsight": "#2ca02c",
}


def gains(rows: dict[str, dict[str, list[float]]]) -> dict[str, np.ndarray]:
    """Per policy, ``[rows, 3]``: the gain over MPDM in percent and its interval."""
    out: dict[str, list[tuple[float, float, float]]] = {p: [] for p in COLORS}
    for values in rows.values():
        for policy in COLORS:
            d = paired_difference(values[REFERENCE], values[policy])
            out[policy].append((d.pct, d.pct_low, d.pct_high))
    return {p: np.array(v, dtype=float) for p, v in out.items()}


def plot(rows: dict[str, dict[str, list[float]]], seeds: int, output: Path) -> Path:
    """Grouped bars, one group per row of the table."""
    per_policy = gains(rows)
    labels = list(rows)
    fig, ax = plt.subplots(figsize=(12, 5.2))
    width = 0.8 / len(per_policy)
    x = np.arange(len(labels))
    for i, (policy, g) in enumerate(per_policy.items()):
        pos = x - 0.4 + width * (i + 0.5)
        err = np.abs(g[:, 1:].T - g[:, 0])
        ax.bar(pos, g[:, 0], width, yerr=err, capsize=1.5, label=policy, color=COLORS[policy])
    ax.axhline(0, color="black", linewidth=0.8)
    ax.set_xticks(x, [label.replace(" (open 60x60)", "").replace("A* ", "") for label in labels])
    ax.tick_params(axis="x", labelrotation=35, labelsize=8)
    ax.set_ylabel("TTD gain over MPDM (%), 95% interval")
    ax.set_title(
        f"Table I (paper mode, 500 decisions): paired gain over MPDM, {seeds} evaluation seeds"
    )
    ax.legend(ncol=6, fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.28))
    ax.grid(axis="y", alpha=0.3)
    fig.tight_layout()
    path = atomic_write(output, lambda fh: fig.savefig(fh, format="png", dpi=110))
    plt.close(fig)
    return path


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, default=Path("benchmarks/data/table1_paper.json"))
    parser.add_argument("--output", type=Path, default=Path("docs/img/table1_ttd.png"))
    args = parser.parse_args()
    data = json.loads(args.data.read_text(encoding="utf-8"))
    print(plot(data["rows"], len(data["seeds"]), args.output))


if __name__ == "__main__":
    main()
