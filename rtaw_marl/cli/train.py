"""``rtaw-train``: train the RTAW policy with PPO (TorchRL).

Examples::

    rtaw-train scenario=poc frames=30000
    rtaw-train recipe=new_map layout=file layout.path=my.map sim.num_robots=20
    rtaw-train sim.num_robots=10 frames=500000 collector.workers=2
    rtaw-train resume=outputs/train/<date>/<time>/checkpoints/last.pt frames=1000000
"""

from __future__ import annotations

from pathlib import Path

from hydra.core.hydra_config import HydraConfig
from omegaconf import DictConfig

from rtaw_marl.cli.common import hydra_entry, typed
from rtaw_marl.training.config import TrainConfig


def run(cfg: DictConfig | TrainConfig) -> None:
    """Train as configured; print the best evaluation, where the checkpoints are and
    (``verdict=true``) whether ``best.pt`` beats the setting's best rule on the
    evaluation seeds."""
    cfg = typed(cfg)
    from rtaw_marl.training.ppo import train

    run_dir = Path(cfg.output_dir or HydraConfig.get().runtime.output_dir)
    result = train(cfg, run_dir)
    if cfg.selection.metric == "tasks_finished":
        best = result.best
        tasks, mpdm = best["tasks_finished"], best["mpdm_tasks_finished"]
        versus = f"vs MPDM {mpdm:.1f} ({100.0 * (tasks - mpdm) / mpdm:+.1f}%)"
        bar = best.get(f"{result.rule}_tasks_finished")  # absent in rows of older runs
        if bar is not None:
            versus += f", {result.rule} {bar:.1f} ({100.0 * (tasks - bar) / bar:+.1f}%)"
        print(f"best greedy tasks finished {tasks:.1f} {versus} after {result.frames} frames")
    else:
        gap = 100.0 * (result.mpdm_ttd - result.best_ttd) / result.mpdm_ttd
        print(
            f"best greedy TTD {result.best_ttd:.2f} vs MPDM {result.mpdm_ttd:.2f} "
            f"({gap:+.1f}%) after {result.frames} frames"
        )
    print(f"checkpoints: {result.best_checkpoint} {result.last_checkpoint}")
    if result.verdict is not None:
        print(result.verdict.line())


main = hydra_entry("train", run)

if __name__ == "__main__":
    main()
