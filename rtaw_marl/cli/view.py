"""``rtaw-view``: one or two episodes in a self-contained, interactive HTML viewer.

Plays ``policy`` (or two policies, side by side on the same seed) with a collision-aware
navigator (``sipp``, ``cbs`` or ``pibt``), checks each schedule with the independent
conflict checker, and writes one HTML file holding the data and the code (no server, no
network; :mod:`rtaw_marl.viz.view`). ``schedule=`` shows saved episodes in LoRR's output
format instead (``rtaw-render output=*.json``, or LoRR's own ``lifelong``), replayed and
checked on the configured map. Progress goes to stderr.

Examples::

    rtaw-view layout=A policy=[mpdm,lookahead] output=view.html
    rtaw-view scenario=lorr tasks.problem=P.json sim.num_robots=10000 policy=mpdm
    rtaw-view scenario=lorr tasks.problem=P.json schedule=lifelong_output.json
"""

from __future__ import annotations

from pathlib import Path

from hydra.core.hydra_config import HydraConfig
from omegaconf import DictConfig

from rtaw_marl.cli.common import (
    as_list,
    hydra_entry,
    policies_from_cfg,
    typed,
)
from rtaw_marl.cli.episode import note, play_checked
from rtaw_marl.errors import ConfigError
from rtaw_marl.evaluation.config import ViewConfig
from rtaw_marl.evaluation.evaluate import SimPolicy
from rtaw_marl.sim.builder import build_sim
from rtaw_marl.sim.core import WarehouseSim
from rtaw_marl.sim.layout import Layout
from rtaw_marl.utils.runs import check_writable_file
from rtaw_marl.viz.episode_data import open_tasks
from rtaw_marl.viz.view import ViewEpisode, file_size, write_view


def _play(sim: WarehouseSim, name: str, policy: SimPolicy, seed: int) -> ViewEpisode:
    metrics, schedule = play_checked(sim, name, policy, seed)
    summary = {
        "TTD": round(float(metrics.ttd), 1),
        "tasks finished": int(metrics.tasks_finished),
        "timesteps": schedule.horizon,
    }
    held = open_tasks(schedule, sim.tasks, sim.task_robot, sim.task_arrival, sim.task_assigned)
    return ViewEpisode(name, schedule, summary, unfinished=held)


def _saved(cfg: ViewConfig) -> tuple[Layout, list[ViewEpisode]]:
    from rtaw_marl.integrations.lorr.output import read_schedule

    paths = as_list(cfg.schedule)
    for path in paths:
        if not Path(path).is_file():
            raise ConfigError(f"schedule={path}: no such file (a LoRR output file)")
    layout = cfg.sim_spec().layout.build()
    episodes = []
    for path in paths:
        note(f"replaying and checking {path}")
        schedule = read_schedule(path, layout)
        finished = int((schedule.task_delivered <= schedule.horizon).sum())
        summary = {"tasks finished": finished, "timesteps": schedule.horizon}
        episodes.append(ViewEpisode(Path(path).stem, schedule, summary))
    return layout, episodes


def run(cfg: DictConfig | ViewConfig) -> Path:
    """Play (or read) the episodes, then write the viewer."""
    cfg = typed(cfg)
    output = check_writable_file(cfg.output or f"{HydraConfig.get().runtime.output_dir}/view.html")
    if output.suffix != ".html":
        raise ConfigError(f"output must end in .html, got {str(output)!r}")
    if cfg.schedule is not None:
        layout, episodes = _saved(cfg)
        title = cfg.title or " vs ".join(e.name for e in episodes)
    else:
        if not cfg.navigator.collision_aware:
            raise ConfigError(
                f"navigator={cfg.navigator.name} moves robots independently (they pass "
                "through each other); view with navigator=sipp, cbs or pibt"
            )
        names = as_list(cfg.policy)
        if len(set(names)) < len(names):
            raise ConfigError(f"policy names the same policy twice: {names}")
        sim = build_sim(cfg.sim_spec())
        policies = policies_from_cfg(cfg, names, sim)
        layout = sim.layout
        episodes = [_play(sim, name, p, int(cfg.seed)) for name, p in policies.items()]
        title = cfg.title or (
            f"{' vs '.join(policies)} | {cfg.navigator.name} | {layout.name} | seed {cfg.seed}"
        )
    path = write_view(output, layout, episodes, title, progress=note)
    for ep in episodes:
        print(f"{ep.name}: " + ", ".join(f"{k} {v}" for k, v in ep.summary.items()))
    print(f"viewer: {path} ({file_size(path.stat().st_size)})")
    return path


main = hydra_entry("view", run)


if __name__ == "__main__":
    main()
