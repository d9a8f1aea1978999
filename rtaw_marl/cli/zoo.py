"""``rtaw-zoo``: retrain the shipped policies with their recipes (:mod:`rtaw_marl.training.zoo`).

Examples::

    rtaw-zoo A_astar_m10                  # one entry, into runs/pretrained/A_astar_m10
    rtaw-zoo --plus --jobs 2              # every RTAW+ entry, two runs at a time
    rtaw-zoo                              # the whole zoo (staged entries last)
    rtaw-zoo --summary                    # the shipped policies' selection figures
    rtaw-zoo --print A_astar_m10_long     # the rtaw-train command only

    # The train entries as one rtaw-train -m sweep on a Hydra launcher (docs/cluster.md):
    rtaw-zoo --launcher joblib
    rtaw-zoo --launcher ray --set hydra.launcher.ray.init.address=auto
    rtaw-zoo --launcher submitit_slurm --set hydra.launcher.partition=cpu

Each entry trains with the exact ``rtaw-train`` command its shipped checkpoint records,
into ``<runs>/<name>`` (``--runs``, default ``runs/pretrained``), then its best
checkpoint is written to ``<ship-to>/<name>.pt`` (default: the package's own folder of
shipped policies), and its training curve to ``<curves>/training_<name>.png`` when
``--curves`` names a folder (the project's docs use ``--curves docs/img``; the command
never writes the docs on its own). Continued and curriculum entries continue their base's run in
``<runs>/<base>``: they run after the others, and ``--launcher`` leaves them out.
Unknown names, a missing base run or a bad option: one ``error:`` line, exit status 2.
"""

from __future__ import annotations

import argparse
import shlex
import subprocess
import sys
from pathlib import Path

from rtaw_marl.cli.plain import OneLineParser, exit_after
from rtaw_marl.training import retrain
from rtaw_marl.training.zoo import RUNS, train_command

__all__ = ["main", "parser", "run"]


def parser() -> argparse.ArgumentParser:
    """The command line of ``rtaw-zoo``."""
    p = OneLineParser(prog="rtaw-zoo", description=__doc__.splitlines()[0])
    p.add_argument("names", nargs="*", help="zoo entries (default: all)")
    p.add_argument("--jobs", type=int, default=1, help="training runs at once")
    p.add_argument("--plus", action="store_true", help="only the RTAW+ entries")
    p.add_argument("--paper", action="store_true", help="only the paper-network entries")
    p.add_argument("--summary", action="store_true", help="print the shipped policies' table")
    p.add_argument("--runs", type=Path, default=RUNS, help="the folder of the runs")
    p.add_argument("--ship-to", type=Path, default=retrain.SHIPPED, help="where .pt files go")
    p.add_argument(
        "--curves", type=Path, help="also copy each training curve here (the docs: docs/img)"
    )
    p.add_argument("--launcher", choices=retrain.LAUNCHERS, help="one rtaw-train -m sweep")
    p.add_argument(
        "--set", action="append", default=[], metavar="KEY=VALUE",
        help="an extra override of the sweep (hydra.launcher.*, collector.*), repeatable",
    )  # fmt: skip
    p.add_argument("--print", action="store_true", help="print the command(s) only")
    p.add_argument(
        "--reselect", action="store_true",
        help="rerun the entries' second selection stage on their finished runs and ship its pick",
    )  # fmt: skip
    p.add_argument("--workers", type=int, default=1, help="second-stage settings at once")
    return p


def run(argv: list[str] | None = None) -> int:
    """Run ``rtaw-zoo`` with ``argv``; returns the exit status.

    Raises:
        RtawError: An unknown entry or launcher, or a missing base run.
    """
    args = parser().parse_args(argv)
    if args.summary:
        print(retrain.summary(args.ship_to))
        return 0
    names = retrain.select(args.names, plus=args.plus, paper=args.paper)
    # The package never writes the docs on its own: curves go where --curves says.
    curves = args.curves
    if args.launcher:
        names, staged = retrain.phases(names)
        if staged:
            print(
                f"note: left out of the sweep (continued and curriculum entries; train them "
                f"without --launcher once their base is trained): {', '.join(staged)}",
                file=sys.stderr,
            )
        cmd = retrain.sweep_command(names, args.launcher, args.set, args.runs)
        if args.print:
            print(shlex.join(cmd))
            return 0
        retrain.train_sweep(names, args.launcher, args.set, args.runs, args.ship_to, curves)
        return 0
    if args.reselect:
        for name in names:
            print(retrain.reselect(name, args.runs, args.ship_to, curves, args.workers))
        return 0
    if args.print:
        for name in names:
            print(shlex.join(train_command(name, args.runs / name, args.runs)))
        return 0
    retrain.train_entries(names, args.jobs, args.runs, args.ship_to, curves)
    return 0


def _failed_run(exc: BaseException) -> str:
    cmd = exc.cmd if isinstance(exc, subprocess.CalledProcessError) else []
    code = getattr(exc, "returncode", "?")
    return f"{shlex.join(map(str, cmd))[:200]} failed ({code})"


def main(argv: list[str] | None = None) -> None:
    """Console entry point: user errors are one ``error:`` line and exit status 2, a
    failed training run exit status 1 (its log is beside the run)."""
    exit_after(run, argv, failures=(subprocess.CalledProcessError,), describe=_failed_run)


if __name__ == "__main__":
    main()
