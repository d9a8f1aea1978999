"""Throughput benchmark of the warehouse simulator and its PettingZoo AEC env.

Prints a markdown table (and writes it with ``--output PATH``). Every figure is the
median of ``--repeats`` timed runs (``time.perf_counter``) after one untimed warm-up
episode; the min-max spread is shown next to it. Benchmarks:

* ``sim+MPDM``: the bare :class:`~rtaw_marl.sim.core.WarehouseSim` stepped by
  ``MPDM.act_sim`` -- decisions per second.
* ``AEC first-valid``: ``env.last()`` + ``env.step(obs["action_mask"].argmax())``
  through the public ``warehouse_v1.env`` (with PettingZoo's order-enforcing
  wrapper) -- steps per second over the live decisions of an episode (reset and the
  final dead steps are not timed).
* ``AEC+MPDM(obs)``: the same loop with ``MPDM.act`` on the observation.
* ``episode``: a whole 1000-robot, 5000-task episode on a 256x256 open grid with A*
  and random tasks, wall time including building the layout and a fresh distance model
  (cold distance-field cache) -- seconds. Run first, so its warm-up also shows the
  cost of loading the numba kernel in a fresh process.

Usage::

    .venv/bin/python -m benchmarks.scripts.bench_env            # full run, a few minutes
    .venv/bin/python -m benchmarks.scripts.bench_env --quick    # tiny sizes, a few seconds
    .venv/bin/python -m benchmarks.scripts.bench_env --output docs/bench.md
"""

from __future__ import annotations

import argparse
import datetime as dt
import os
import platform
import statistics
import subprocess
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

import rtaw_marl
from rtaw_marl import warehouse_v1
from rtaw_marl.policies import MPDM, RBTS, BaselinePolicy
from rtaw_marl.sim.builder import SimSpec, build_sim
from rtaw_marl.sim.core import WarehouseSim

REPO_ROOT = Path(__file__).resolve().parents[2]
USC_64 = REPO_ROOT.parent / "shared" / "maps" / "rtaw" / "usc_64.cfg"
QUEUE_LEN = 10


@dataclass(frozen=True)
class Setting:
    """A layout and navigator to benchmark on."""

    label: str
    layout: Any
    navigator: str


@dataclass(frozen=True)
class Sizes:
    """Problem sizes of a run (full or ``--quick``)."""

    robots: tuple[int, ...]
    num_tasks: int
    repeats: int
    episode_robots: int
    episode_tasks: int
    episode_grid: int


FULL = Sizes(
    robots=(10, 100, 1000),
    num_tasks=5000,
    repeats=3,
    episode_robots=1000,
    episode_tasks=5000,
    episode_grid=256,
)
QUICK = Sizes(
    robots=(10, 100),
    num_tasks=300,
    repeats=1,
    episode_robots=100,
    episode_tasks=300,
    episode_grid=64,
)

#: ``(benchmark, M) -> (comparison, threshold)``; the targets of docs/performance.md.
TARGETS: dict[tuple[str, int], tuple[str, float]] = {
    ("sim+MPDM", 100): (">=", 30_000.0),
    ("AEC first-valid", 100): (">=", 15_000.0),
    ("AEC first-valid", 1000): (">=", 5_000.0),
    ("episode MPDM", 1000): ("<", 10.0),
}


@dataclass
class Row:
    """One line of the result table."""

    benchmark: str
    setting: str
    robots: int
    tasks: int
    samples: list[float]
    unit: str

    @property
    def median(self) -> float:
        return statistics.median(self.samples)

    def target(self, quick: bool) -> tuple[str, str]:
        """The target text and whether it is met (``"-"`` when none applies)."""
        # Throughput targets apply to both settings (direct grid and usc_64 with A*).
        key = (self.benchmark, self.robots)
        if key not in TARGETS:
            return "", "-"
        op, threshold = TARGETS[key]
        text = f"{op} {_fmt(threshold)}"
        if quick:
            return text, "n/a (quick)"
        met = self.median >= threshold if op == ">=" else self.median < threshold
        return text, "yes" if met else "**no**"


def _fmt(value: float) -> str:
    if value >= 100:
        return f"{value:,.0f}"
    if value >= 10:
        return f"{value:.1f}"
    return f"{value:.2f}"


# --------------------------------------------------------------------------- timed loops
def sim_episode(sim: WarehouseSim, policy: BaselinePolicy, seed: int) -> tuple[int, float]:
    """Run one episode of the bare simulator; ``(decisions, seconds)`` of the step loop."""
    sim.reset(seed)
    policy.reset(seed)
    act, step = policy.act_sim, sim.step
    start = time.perf_counter()
    while not sim.done:
        step(act(sim))
    return sim.decisions, time.perf_counter() - start


def aec_episode(
    env: Any, choose: Callable[[dict[str, np.ndarray]], int], seed: int
) -> tuple[int, float]:
    """Run the live part of one AEC episode; ``(steps, seconds)`` of observe + step."""
    env.reset(seed=seed)
    last, step = env.last, env.step
    steps = 0
    start = time.perf_counter()
    while True:
        obs, _, terminated, truncated, _ = last()
        if terminated or truncated:
            break
        step(choose(obs))
        steps += 1
    return steps, time.perf_counter() - start


def first_valid(obs: dict[str, np.ndarray]) -> int:
    """The first legal queue slot."""
    return int(obs["action_mask"].argmax())


def repeat(run: Callable[[int], tuple[int, float]], repeats: int, per_second: bool) -> list[float]:
    """One warm-up call, then ``repeats`` timed calls (seeds 1, 2, ...)."""
    run(0)
    samples = []
    for seed in range(1, repeats + 1):
        count, seconds = run(seed)
        samples.append(count / seconds if per_second else seconds)
    return samples


# --------------------------------------------------------------------------- benchmarks
def bench_full_episode(sizes: Sizes, policy_cls: type[BaselinePolicy]) -> tuple[Row, float]:
    """Whole episodes including distance model construction; also the warm-up's wall time."""
    grid = {"name": "open", "width": sizes.episode_grid, "height": sizes.episode_grid}
    sim_keys = {
        "num_robots": sizes.episode_robots,
        "num_tasks": sizes.episode_tasks,
        "queue_len": QUEUE_LEN,
    }

    def run(seed: int) -> tuple[int, float]:
        start = time.perf_counter()
        sim = build_sim(SimSpec.of(sim_keys, grid, "astar", "random"))
        policy = policy_cls()
        decisions, _ = sim_episode(sim, policy, seed)
        return decisions, time.perf_counter() - start

    warm_start = time.perf_counter()
    run(0)
    warm = time.perf_counter() - warm_start
    samples = [run(seed)[1] for seed in range(1, sizes.repeats + 1)]
    label = f"open {sizes.episode_grid}x{sizes.episode_grid}, A*, random"
    row = Row(
        f"episode {policy_cls.name.upper()}",
        label,
        sizes.episode_robots,
        sizes.episode_tasks,
        samples,
        "s / episode",
    )
    return row, warm


def bench_throughput(sizes: Sizes, settings: Sequence[Setting]) -> list[Row]:
    """Bare simulator and AEC env throughput for every setting and robot count."""
    rows: list[Row] = []
    for setting in settings:
        for m in sizes.robots:
            sim_keys = {"num_robots": m, "num_tasks": sizes.num_tasks, "queue_len": QUEUE_LEN}
            sim = build_sim(SimSpec.of(sim_keys, setting.layout, setting.navigator, "designated"))
            mpdm = MPDM()
            samples = repeat(lambda s, sim=sim, p=mpdm: sim_episode(sim, p, s), sizes.repeats, True)
            rows.append(Row("sim+MPDM", setting.label, m, sizes.num_tasks, samples, "decisions/s"))
            _progress(rows[-1])

            env = warehouse_v1.env(**sim_keys, layout=setting.layout, navigator=setting.navigator)
            samples = repeat(
                lambda s, env=env: aec_episode(env, first_valid, s), sizes.repeats, True
            )
            rows.append(
                Row("AEC first-valid", setting.label, m, sizes.num_tasks, samples, "steps/s")
            )
            _progress(rows[-1])

            policy = MPDM(scale=env.unwrapped.scale)

            def mpdm_obs(seed: int, env: Any = env, policy: MPDM = policy) -> tuple[int, float]:
                policy.reset(seed)
                return aec_episode(env, policy.act, seed)

            samples = repeat(mpdm_obs, sizes.repeats, True)
            rows.append(Row("AEC+MPDM(obs)", setting.label, m, sizes.num_tasks, samples, "steps/s"))
            _progress(rows[-1])
    return rows


def _progress(row: Row) -> None:
    print(
        f"  {row.benchmark:<16} {row.setting:<28} M={row.robots:<5} {_fmt(row.median)} {row.unit}",
        file=sys.stderr,
        flush=True,
    )


# --------------------------------------------------------------------------- report
def git_revision() -> str:
    """Short commit of the checkout, flagged when ``rtaw_marl/`` has uncommitted changes."""
    try:
        head = subprocess.run(
            ["git", "rev-parse", "--short", "HEAD"],
            cwd=REPO_ROOT,
            capture_output=True,
            text=True,
            check=True,
        ).stdout.strip()
        dirty = subprocess.run(
            ["git", "status", "--porcelain", "--", "rtaw_marl"],
            cwd=REPO_ROOT,
            capture_output=True,
            text=True,
            check=True,
        ).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"
    return f"{head} + uncommitted changes in rtaw_marl/" if dirty else head


def machine_lines(started: dt.datetime) -> list[str]:
    """Start date, machine, code revision and library versions."""
    import numba
    import pettingzoo

    return [
        f"- code: rtaw_marl {rtaw_marl.__version__}, git {git_revision()}",
        f"- date: {started.isoformat(timespec='seconds')} (start of the run)",
        f"- machine: {platform.platform()}, {platform.machine()}, "
        f"os.cpu_count()={os.cpu_count()}, processor={platform.processor() or 'n/a'}",
        f"- python {platform.python_version()}, numpy {np.__version__}, numba {numba.__version__}, "
        f"pettingzoo {pettingzoo.__version__}",
    ]


def render_table(rows: Sequence[Row], quick: bool) -> str:
    """The results as a markdown table."""
    lines = [
        "| benchmark | setting | M | N | tasks | median | spread (min-max) | unit | target | met |",
        "|---|---|---:|---:|---:|---:|---|---|---|---|",
    ]
    for row in rows:
        target, met = row.target(quick)
        spread = f"{_fmt(min(row.samples))}-{_fmt(max(row.samples))}"
        lines.append(
            f"| {row.benchmark} | {row.setting} | {row.robots} | {QUEUE_LEN} | {row.tasks} | "
            f"{_fmt(row.median)} | {spread} | {row.unit} | {target} | {met} |"
        )
    return "\n".join(lines)


def main(argv: Sequence[str] | None = None) -> str:
    """Run the benchmark; returns the markdown report that was printed."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="tiny sizes: a smoke run")
    parser.add_argument("--output", type=Path, help="also write the report to this file")
    parser.add_argument("--repeats", type=int, help="timed runs per figure (default 3, quick 1)")
    args = parser.parse_args(argv)
    sizes = QUICK if args.quick else FULL
    if args.repeats is not None:
        if args.repeats < 1:
            parser.error("--repeats must be >= 1")
        sizes = Sizes(**{**sizes.__dict__, "repeats": args.repeats})

    settings = [
        Setting("open 60x60, direct", {"name": "open", "width": 60, "height": 60}, "direct")
    ]
    notes = []
    if USC_64.is_file():
        settings.append(Setting("usc_64.cfg, A*", str(USC_64), "astar"))
    else:
        notes.append(f"- {USC_64} not found: the usc_64 rows were skipped.")

    started = dt.datetime.now().astimezone()
    print(f"benchmarking ({'quick' if args.quick else 'full'})...", file=sys.stderr, flush=True)
    episode_mpdm, cold = bench_full_episode(sizes, MPDM)
    _progress(episode_mpdm)
    episode_rbts, _ = bench_full_episode(sizes, RBTS)
    _progress(episode_rbts)
    rows = bench_throughput(sizes, settings)
    rows += [episode_mpdm, episode_rbts]

    notes.append(
        "- episode rows: wall time of one whole episode including building the layout and a "
        "fresh A* distance model (cold distance-field cache); throughput rows reuse one "
        "simulator/env per setting, so their field cache is warm after the warm-up."
    )
    notes.append(
        f"- first MPDM episode of this process (its warm-up, incl. loading the numba BFS "
        f"kernel and all of its distance fields cold): {cold:.2f} s"
    )
    report = "\n".join(
        [
            f"## Benchmark ({'quick smoke run' if args.quick else 'full run'})",
            "",
            *machine_lines(started),
            f"- median of {sizes.repeats} timed run(s) after 1 warm-up; queue N={QUEUE_LEN}; "
            f"{sizes.num_tasks} designated tasks per throughput episode",
            "",
            render_table(rows, args.quick),
            "",
            *notes,
        ]
    )
    print(report)
    if args.output is not None:
        args.output.parent.mkdir(parents=True, exist_ok=True)
        args.output.write_text(report + "\n")
    return report


if __name__ == "__main__":
    main()
