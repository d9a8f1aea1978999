"""Plots of training runs."""

from __future__ import annotations

from pathlib import Path

__all__ = ["plot_training_curve"]


def plot_training_curve(history: list[dict[str, float]], path: Path) -> Path | None:
    """Greedy evaluation TTD against frames, with MPDM's TTD on the same seeds.

    Returns:
        The PNG path, or ``None`` when there is nothing to plot.
    """
    if not history:
        return None
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    frames = [row["frames"] for row in history]
    fig, ax = plt.subplots(figsize=(6, 3.5), dpi=120)
    ax.plot(frames, [row["ttd"] for row in history], marker="o", label="RTAW (greedy)")
    ax.axhline(history[0]["mpdm_ttd"], color="tab:red", linestyle="--", label="MPDM")
    for rule in ("lookahead", "pair_greedy"):  # the setting's strongest rule, if logged
        if f"{rule}_ttd" in history[0]:
            ax.axhline(history[0][f"{rule}_ttd"], color="tab:green", linestyle=":",
                       label=rule)  # fmt: skip
    ax.set_xlabel("frames (decisions)")
    ax.set_ylabel("mean episode TTD (s)")
    ax.set_title("Evaluation on fixed seeds")
    ax.legend()
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path)
    plt.close(fig)
    return path
