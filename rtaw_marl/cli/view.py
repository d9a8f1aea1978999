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

import math
from pathlib import Path

from hydra.core.hydra_config import HydraConfig
from omegaconf import DictConfig

from rtaw_marl.cli.common import (
    as_list,
    hydra_entry,
    policies_from_cfg,
    policy_names,
    policy_specs,
    typed,
)
from rtaw_marl.cli.episode import note, play_checked
from rtaw_marl.errors import ConfigError
from rtaw_marl.evaluation.config import ViewConfig
from rtaw_marl.evaluation.evaluate import SimPolicy
from rtaw_marl.sim.builder import SimSpec, build_sim
from rtaw_marl.sim.core import WarehouseSim
from rtaw_marl.sim.layout import Layout
from rtaw_marl.viz.budget import check_cost, play_cost, saved_cost
from rtaw_marl.viz.episode_data import open_tasks
from rtaw_marl.viz.output_file import claimed_output, config_inputs
from rtaw_marl.viz.schedule_file import read_schedule_file
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


def _saved(cfg: ViewConfig, paths: list[str]) -> tuple[Layout, list[ViewEpisode]]:
    """Each file read and checked in full (:mod:`rtaw_marl.viz.schedule_file`)."""
    layout = cfg.sim_spec().layout.build()
    more = "show one schedule file at a time" if len(paths) > 1 else "show a shorter episode"
    episodes: list[ViewEpisode] = []

    def budget(robots: int, timesteps: int) -> None:
        # Side by side episodes share one clock and fleet: a file still to come is as
        # large as this one; one already read is in memory (and off what is available).
        check_cost(saved_cost(robots, timesteps, len(paths) - len(episodes)), more, note)

    for path in paths:
        # No progress line before it: a bad file is its one error line (a big file's
        # estimate is announced by the budget once its fields are checked).
        saved = read_schedule_file(path, layout, budget)
        summary = {"tasks finished": saved.tasks_finished, "timesteps": saved.schedule.horizon}
        episodes.append(ViewEpisode(Path(path).stem, saved.schedule, summary))
    return layout, episodes


def _policy_names(cfg: ViewConfig) -> list[str]:
    """The policies to play, checked (nothing is loaded yet)."""
    if not cfg.navigator.collision_aware:
        raise ConfigError(
            f"navigator={cfg.navigator.name} moves robots independently (they pass "
            "through each other); view with navigator=sipp, cbs or pibt"
        )
    names = as_list(cfg.policy)
    if len(set(names)) < len(names):
        raise ConfigError(f"policy names the same policy twice: {names}")
    # The deprecated name translated once, so its warning is printed once.
    return policy_names(names)


def _check_play_cost(spec: SimSpec, episodes: int) -> None:
    """Estimate the run from its setting; refuse one that cannot fit in memory.

    A horizon episode's length is ``sim.horizon``; one that runs until its tasks are
    done takes about one trip across the map (``W + H`` timesteps: to the pickup, then
    to the delivery) per task a robot serves.
    """
    sim = spec.sim
    size = spec.layout.size()
    if size is None:  # a map file: its size is known once it is read (cached for later)
        grid = spec.layout.build()
        size = (grid.width, grid.height)
    width, height = size
    fewer = f", or view one policy instead of {episodes}" if episodes > 1 else ""
    if sim.episode_mode == "horizon":
        timesteps = int(sim.horizon)
        lower = f"lower sim.horizon (now {timesteps}) or sim.num_robots (now {sim.num_robots})"
    else:
        timesteps = math.ceil(sim.num_tasks / sim.num_robots) * (width + height)
        lower = f"lower sim.num_tasks (now {sim.num_tasks})"
    cost = play_cost(int(sim.num_robots), timesteps, episodes, width * height)
    check_cost(cost, lower + fewer, note)


def _played(cfg: ViewConfig, names: list[str]) -> tuple[Layout, list[ViewEpisode], str]:
    """Play every policy on the same seed."""
    sim = build_sim(cfg.sim_spec())
    policies = policies_from_cfg(cfg, names, sim)
    episodes = [_play(sim, name, p, int(cfg.seed)) for name, p in policies.items()]
    title = cfg.title or (
        f"{' vs '.join(policies)} | {cfg.navigator.name} | {sim.layout.name} | seed {cfg.seed}"
    )
    return sim.layout, episodes, title


def run(cfg: DictConfig | ViewConfig) -> Path:
    """Check the setting, claim the output, play (or read) the episodes, then write the
    viewer."""
    cfg = typed(cfg)
    output = Path(cfg.output or f"{HydraConfig.get().runtime.output_dir}/view.html")
    if output.suffix != ".html":
        raise ConfigError(f"output must end in .html, got {str(output)!r}")
    paths = as_list(cfg.schedule)
    for path in paths:
        if not Path(path).is_file():
            raise ConfigError(f"schedule={path}: no such file (a LoRR output file)")
    if not paths:
        names = _policy_names(cfg)
        _check_play_cost(cfg.sim_spec(), len(policy_specs(cfg, names)))
    with claimed_output(output, config_inputs(cfg), progress=note) as output:
        if paths:
            layout, episodes = _saved(cfg, paths)
            title = cfg.title or " vs ".join(e.name for e in episodes)
        else:
            layout, episodes, title = _played(cfg, names)
        path = write_view(output, layout, episodes, title, progress=note)
    for ep in episodes:
        print(f"{ep.name}: " + ", ".join(f"{k} {v}" for k, v in ep.summary.items()))
    print(f"viewer: {path} ({file_size(path.stat().st_size)})")
    return path


main = hydra_entry("view", run)


if __name__ == "__main__":
    main()
