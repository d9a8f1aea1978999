"""Throughput of the PettingZoo env through TorchRL's ``PettingZooWrapper`` (interop route).

For each wrapper, observation option (``full``, ``compact``), feature format (``dict``,
``flat``) and robot count ``M``, wraps ``warehouse_v1.env(...)`` with all robots in one
group and times ``env.step(td)`` with the first valid slot of the acting row's mask (an
argmax over the mask tensor): steps per second, median of ``--repeats`` timed runs after
a few warm-up steps, min-max spread beside it. Layout: a 60x60 open grid with the
``direct`` navigator, queue ``N = 10``, designated tasks. Two wrappers:

* ``stock``: TorchRL's ``PettingZooWrapper(env, use_mask=True,
  group_map=MarlGroupMapType.ALL_IN_ONE_GROUP)``, which fills its output agent by agent;
* ``vectorised``: :class:`rtaw_marl.envs.torchrl_wrapper.WarehouseWrapper`, the same
  wrapper (a subclass, bit-identical output) filling every robot's row at once; what
  ``rtaw_marl/training/interop.py`` builds.

A ``no-op`` row runs the stock wrapper over an AEC env that does nothing, with the spaces
of the compact flat observation and the same nine info keys: the stock wrapper's own
cost per step, a ceiling for any env through it. ``no-op, no infos`` leaves the infos
empty: the difference is what the wrapper spends copying infos, agent by agent.

torch runs on one thread: the wrapper clones its ``[M, ...]`` output tensordict every
step, and on a shared 2-core machine torch's two intra-op threads turned that clone into
milliseconds of waiting (2.3-8.7 ms per step at ``M = 100``, 0.04 ms on one thread).

Usage::

    .venv/bin/python -m benchmarks.scripts.bench_wrapper            # M = 10, 100, 1000: minutes
    .venv/bin/python -m benchmarks.scripts.bench_wrapper --quick    # M = 10, 100, few steps
    .venv/bin/python -m benchmarks.scripts.bench_wrapper --output wrapper.md
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import sys
import time
import warnings
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path
from typing import Any, ClassVar

import numpy as np
import pettingzoo
import torch
import torchrl
from gymnasium import spaces
from pettingzoo import AECEnv
from torchrl.envs import PettingZooWrapper
from torchrl.envs.libs.pettingzoo import MarlGroupMapType

from rtaw_marl import warehouse_v1
from rtaw_marl.decision.observations import ObservationLayout
from rtaw_marl.envs.pettingzoo import zero_info
from rtaw_marl.envs.spaces import agent_space
from rtaw_marl.envs.torchrl_wrapper import WarehouseWrapper

QUEUE_LEN = 10
LAYOUT = {"name": "open", "width": 60, "height": 60}
#: Timed steps per run, per ``M`` (about a second or more each).
STEPS = {10: 300, 100: 100, 1000: 10}
#: The wrappers compared (``--wrappers``).
WRAPPERS = ("stock", "vectorised")
#: The issue's targets for the compact observation: ``M -> steps/s``.
TARGETS = {100: 100.0, 1000: 10.0}


class NoOpEnv(AECEnv):
    """An AEC env that computes nothing, with the compact flat layout's spaces and infos."""

    metadata: ClassVar[dict[str, Any]] = {"name": "noop_v0"}

    def __init__(self, num_robots: int, infos: bool = True) -> None:
        super().__init__()
        self._info = zero_info() if infos else {}
        layout = ObservationLayout("compact", "flat", num_robots, QUEUE_LEN)
        self.possible_agents = [f"robot_{i}" for i in range(num_robots)]
        self.observation_spaces = dict.fromkeys(self.possible_agents, agent_space(layout))
        self.action_spaces = dict.fromkeys(self.possible_agents, spaces.Discrete(QUEUE_LEN))
        self._features = np.zeros(layout.flat_size, np.float32)
        self._mask = np.ones(QUEUE_LEN, np.int8)
        self._turn = 0

    def observation_space(self, agent: str) -> spaces.Space:
        return self.observation_spaces[agent]

    def action_space(self, agent: str) -> spaces.Space:
        return self.action_spaces[agent]

    def reset(self, seed: int | None = None, options: dict | None = None) -> None:
        self.agents = self.possible_agents[:]
        self.rewards = dict.fromkeys(self.agents, 0.0)
        self._cumulative_rewards = dict.fromkeys(self.agents, 0.0)
        self.terminations = dict.fromkeys(self.agents, False)
        self.truncations = dict.fromkeys(self.agents, False)
        self.infos = dict.fromkeys(self.agents, self._info)
        self.agent_selection = self.agents[0]

    def observe(self, agent: str) -> dict[str, np.ndarray]:
        return {"observation": self._features, "action_mask": self._mask}

    def step(self, action: int | None) -> None:
        self._turn += 1
        self.agent_selection = self.agents[self._turn % len(self.agents)]


@dataclass
class Row:
    """One line of the result table."""

    env: str
    wrapper: str
    observation: str
    obs_format: str
    robots: int
    build_s: float
    samples: list[float] = field(default_factory=list)

    @property
    def median(self) -> float:
        return statistics.median(self.samples)


def wrap(aec: AECEnv, wrapper: str) -> PettingZooWrapper:
    if wrapper == "vectorised":
        return WarehouseWrapper(aec, seed=0)
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=r"PettingZoo in TorchRL is tested using")
        return PettingZooWrapper(
            aec, use_mask=True, group_map=MarlGroupMapType.ALL_IN_ONE_GROUP, seed=0
        )


def measure(
    make: Callable[[], AECEnv], label: tuple[str, str, str, str], m: int, steps: int, repeats: int
) -> Row:
    """Build the wrapped env, then ``repeats`` timed runs of ``steps`` steps."""
    start = time.perf_counter()
    env = wrap(make(), label[1])
    row = Row(*label, m, time.perf_counter() - start)
    td = env.reset()
    for run in range(repeats + 1):
        start = time.perf_counter()
        for _ in range(steps if run else max(steps // 10, 2)):  # run 0: the warm-up
            td["agents", "action"] = td["agents", "action_mask"].to(torch.uint8).argmax(-1)
            td = env.step(td)["next"]
        if run:
            row.samples.append(steps / (time.perf_counter() - start))
    env.close()
    print(
        f"  {row.env:<15} {row.wrapper:<10} {row.observation:<8} {row.obs_format:<5} M={m:<5} "
        f"{row.median:,.1f} steps/s (build {row.build_s:.2f} s)",
        file=sys.stderr,
        flush=True,
    )
    return row


def run_all(
    robots: tuple[int, ...], repeats: int, quick: bool, wrappers: tuple[str, ...] = WRAPPERS
) -> list[Row]:
    rows = []
    for m in robots:
        steps = max(STEPS[m] // 10, 3) if quick else STEPS[m]
        total = (repeats + 1) * steps + 10
        for observation in ("compact", "full"):
            for obs_format in ("dict", "flat"):
                make = partial(
                    warehouse_v1.env, num_robots=m, num_tasks=total, queue_len=QUEUE_LEN,
                    layout=LAYOUT, navigator="direct", observation=observation,
                    obs_format=obs_format,
                )  # fmt: skip
                for wrapper in wrappers:
                    label = ("warehouse", wrapper, observation, obs_format)
                    rows.append(measure(make, label, m, steps, repeats))
        if "stock" in wrappers:
            noop = ("no-op", "stock", "compact", "flat")
            rows.append(measure(partial(NoOpEnv, m), noop, m, steps, repeats))
            noop = ("no-op, no infos", "stock", "compact", "flat")
            rows.append(measure(partial(NoOpEnv, m, infos=False), noop, m, steps, repeats))
    return rows


def render(rows: list[Row], quick: bool) -> str:
    """The markdown table; ``speed-up`` is vectorised over stock, both from this run."""
    stock = {
        (r.observation, r.obs_format, r.robots): r.median
        for r in rows
        if r.env == "warehouse" and r.wrapper == "stock"
    }
    lines = [
        "| env | wrapper | observation | format | M | median steps/s | spread (min-max) "
        "| speed-up | build s | target | met |",
        "|---|---|---|---|---:|---:|---|---:|---:|---|---|",
    ]
    for row in rows:
        target, met, ratio = "", "-", ""
        if row.env == "warehouse" and row.observation == "compact" and row.robots in TARGETS:
            target = f">= {TARGETS[row.robots]:g}"
            met = (
                "n/a (quick)"
                if quick
                else ("yes" if row.median >= TARGETS[row.robots] else "**no**")
            )
        base = stock.get((row.observation, row.obs_format, row.robots))
        if row.env == "warehouse" and row.wrapper == "vectorised" and base:
            ratio = f"{row.median / base:,.1f}x"
        spread = f"{min(row.samples):,.1f}-{max(row.samples):,.1f}"
        lines.append(
            f"| {row.env} | {row.wrapper} | {row.observation} | {row.obs_format} | "
            f"{row.robots} | {row.median:,.1f} | {spread} | {ratio} | {row.build_s:.2f} | "
            f"{target} | {met} |"
        )
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> str:
    """Run the benchmark; returns the markdown report that was printed."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="M = 10, 100 and few steps")
    parser.add_argument("--repeats", type=int, default=3, help="timed runs per figure")
    parser.add_argument("--output", type=Path, help="also write the report to this file")
    parser.add_argument(
        "--wrappers", nargs="+", choices=WRAPPERS, default=list(WRAPPERS), help="which to time"
    )
    args = parser.parse_args(argv)
    if args.repeats < 1:
        parser.error("--repeats must be >= 1")
    torch.set_num_threads(1)
    repeats = 1 if args.quick else args.repeats
    load = os.getloadavg()[0]
    started = time.strftime("%Y-%m-%d %H:%M %Z")
    robots = (10, 100) if args.quick else (10, 100, 1000)
    rows = run_all(robots, repeats, args.quick, tuple(args.wrappers))
    report = "\n".join(
        [
            f"## PettingZooWrapper benchmark ({'quick smoke run' if args.quick else 'full run'})",
            "",
            f"- date: {started}; load average {load:.1f} at the start, "
            f"{os.getloadavg()[0]:.1f} at the end",
            f"- machine: {platform.platform()}, os.cpu_count()={os.cpu_count()}, no GPU used",
            f"- python {platform.python_version()}, torch {torch.__version__} (1 thread), "
            f"torchrl {torchrl.__version__}, pettingzoo {pettingzoo.__version__}",
            f"- median of {repeats} timed run(s) after a warm-up; N={QUEUE_LEN}; open 60x60, "
            "direct navigator; targets apply to the compact observation",
            "",
            render(rows, args.quick),
        ]
    )
    print(report)
    if args.output is not None:
        args.output.write_text(report + "\n")
    return report


if __name__ == "__main__":
    main()
