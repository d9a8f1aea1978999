"""``rtaw-render``: play one episode and save it as an animated GIF (or, with an
``output`` ending in ``.json``, in LoRR's output format, for its viewer PlanViz).

The episode runs with a collision-aware navigator (``sipp`` by default, ``cbs`` or
``pibt``), with progress on stderr, is checked by the independent conflict checker, then
drawn: robots moving along their paths, queued tasks, tasks on their way to pickup,
carried tasks and their destinations.

Examples::

    rtaw-render layout=A policy=pretrained pretrained=A_astar_m10 output=episode.gif
    rtaw-render navigator=cbs sim.num_tasks=20 every=2 fps=12
    rtaw-render scenario=lorr tasks.problem=P.json sim.horizon=500 output=episode.json

A GIF shows robots in 18 cycling colours: to follow one robot in a large fleet, use
``rtaw-view`` (an interactive page: search a robot or task and follow it).
"""

from __future__ import annotations

from pathlib import Path

from hydra.core.hydra_config import HydraConfig
from omegaconf import DictConfig

from rtaw_marl.cli.common import hydra_entry, policies_from_cfg, typed
from rtaw_marl.cli.episode import note, play_checked
from rtaw_marl.errors import ConfigError
from rtaw_marl.evaluation.config import RenderConfig
from rtaw_marl.sim.builder import build_sim
from rtaw_marl.viz.gif import render_gif
from rtaw_marl.viz.output_file import claimed_output, config_inputs


def run(cfg: DictConfig | RenderConfig) -> Path:
    """Play ``cfg.policy`` on seed ``cfg.seed``, check the schedule, write the GIF."""
    cfg = typed(cfg)
    if not isinstance(cfg.policy, str):
        raise ConfigError(f"policy must name one policy, got {cfg.policy}")
    if isinstance(cfg.seed, bool) or not isinstance(cfg.seed, int):
        raise ConfigError(f"seed must be an integer, got {cfg.seed!r}")
    if not cfg.navigator.collision_aware:
        raise ConfigError(
            f"navigator={cfg.navigator.name} moves robots independently (they pass through "
            "each other); render with navigator=sipp or navigator=cbs"
        )
    output = Path(cfg.output or f"{HydraConfig.get().runtime.output_dir}/episode.gif")
    if output.suffix not in (".gif", ".json"):
        raise ConfigError(
            f"output must end in .gif (an animation) or .json (LoRR's output format), got "
            f"{str(output)!r}"
        )
    # Claimed before the episode is played and drawn, which can take minutes: a second
    # run writing the same file fails now, and a file the run reads is never replaced.
    with claimed_output(output, config_inputs(cfg), progress=note) as output:
        return _render(cfg, output)


def _render(cfg: RenderConfig, output: Path) -> Path:
    """Play the episode, check it, and write ``output`` (held by the caller)."""
    sim = build_sim(cfg.sim_spec())
    (name, policy), *_ = policies_from_cfg(cfg, [cfg.policy], sim).items()
    metrics, schedule = play_checked(sim, name, policy, int(cfg.seed))
    if output.suffix == ".json":
        from rtaw_marl.integrations.lorr.output import write_episode

        path = write_episode(schedule, output, horizon=sim.config.horizon)
        print(
            f"{name}: {metrics.tasks_finished} tasks finished, {schedule.horizon + 1} time "
            f"steps, schedule checked\nLoRR output (PlanViz): {path}"
        )
        return path
    title = f"{name} | {cfg.navigator.name} | {sim.layout.name} | seed {cfg.seed}"
    note(f"drawing {output}")
    path = render_gif(
        sim.layout,
        schedule,
        output,
        fps=int(cfg.fps),
        cell_px=cfg.cell_px,
        start=int(cfg.start),
        stop=cfg.stop,
        every=int(cfg.every),
        max_frames=int(cfg.max_frames),
        title=title,
    )
    print(
        f"{name}: TTD {metrics.ttd:.0f} s, makespan {metrics.makespan:.0f} s, "
        f"{len(schedule.tasks)} tasks, {schedule.horizon + 1} time steps, schedule checked"
    )
    print(f"gif: {path}")
    return path


main = hydra_entry("render", run)


if __name__ == "__main__":
    main()
