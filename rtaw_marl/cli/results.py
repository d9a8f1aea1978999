"""``rtaw-results``: combine a sweep's ``results.json`` files into one table and one plot.

Examples::

    rtaw-results multirun/eval/2026-12-04/12-00-00_123      # every job of one sweep
    rtaw-results multirun/eval/2026-12-04 runs/big/results.json --output combined/
    rtaw-results SWEEP --reference lookahead --compare-to rbts
    rtaw-results SWEEP --metric makespan --x sim.num_robots

Every ``results.json`` under the folders given (and every file named) is read; rows
are grouped by setting, named by the overrides that differ between jobs (a sweep over
``policy`` merges into one setting). The table (the mean of ``--metric``, TTD by
default, with its 95% interval, the paired difference with MPDM or ``--reference``, as
``rtaw-eval`` prints them) goes to stdout and, with a CSV, a JSON, a PNG plot
(:mod:`~rtaw_marl.evaluation.combine_plot`: lines over a numeric swept key, one panel
per value of the others, the differences below) and the per-episode table of every
metric, into ``<output>/combined.*`` and ``combined_episodes.csv`` (default: the one
folder given), held for the run (another ``rtaw-results`` into it is refused) and
written as one set: all five are rendered first, then renamed in together, so Ctrl-C or
SIGTERM (one ``interrupted:`` line saying whether they were written, exit 130 or 143)
never leaves a mix of new and old files. No results found, an unreadable or foreign
file (each is checked in full first:
:func:`~rtaw_marl.evaluation.results_file.read_results`), a metric the files do not all
hold, an ``--x`` that is not swept, an output that would replace one of the inputs, or
two jobs of one setting that disagree: one ``error:`` line, exit status 2, before
anything is written.
"""

from __future__ import annotations

import argparse
import os
import signal
import sys
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path

from rtaw_marl.cli.plain import OneLineParser, exit_after
from rtaw_marl.errors import ConfigError
from rtaw_marl.evaluation.combine import (
    check_metric,
    combine,
    evaluated_policies,
    find_results,
    load_jobs,
)
from rtaw_marl.evaluation.combine_output import (
    OUTPUT_NAMES,
    OUTPUT_STEM,
    CombinedFiles,
    combined_paths,
    combined_table,
    render_combined,
)
from rtaw_marl.utils.runs import claim_folder
from rtaw_marl.utils.signals import Interrupted, terminate_as_interrupt

__all__ = ["main", "parser", "run"]

#: rtaw-eval's main baseline.
REFERENCE = "mpdm"

#: The combined files, for messages.
OUTPUTS = f"{OUTPUT_STEM}.{{txt,csv,json,png}} and {OUTPUT_NAMES['episodes']}"


def parser() -> argparse.ArgumentParser:
    """The command line of ``rtaw-results``."""
    p = OneLineParser(prog="rtaw-results", description=__doc__.splitlines()[0])
    p.add_argument("paths", nargs="+", type=Path, help="sweep folders or results.json files")
    p.add_argument(
        "--output", type=Path,
        help="folder of combined.{txt,csv,json,png} and combined_episodes.csv (default: "
        "the one folder given)",
    )  # fmt: skip
    p.add_argument(
        "--reference", help=f"the main baseline of the comparisons (default: {REFERENCE})"
    )
    p.add_argument("--compare-to", help="a second baseline, as rtaw-eval's compare_to")
    p.add_argument(
        "--metric", default="ttd", metavar="NAME",
        help="the metric of the table and plot: any the results hold (ttd, makespan, "
        "tasks_finished, wait_mean, ...; default: ttd)",
    )  # fmt: skip
    p.add_argument(
        "--x", metavar="KEY",
        help="the swept key on the plot's x axis (default: the first numeric one)",
    )  # fmt: skip
    return p


def _output(args: argparse.Namespace) -> Path:
    if args.output is not None:
        return args.output
    if len(args.paths) == 1 and args.paths[0].is_dir():
        return args.paths[0]
    raise ConfigError("give --output FOLDER when combining files or several folders")


def _check_not_inputs(folder: Path, found: Sequence[Path], named: Iterable[Path]) -> None:
    """Refuse an output folder where a combined file would replace one of the inputs.

    A file is compared by where it really is (symlinks and ``..`` resolved) and, for a
    file named on the command line, also by the name given: an atomic write replaces
    the name in the resolved folder, which may be a symlink to an input.
    """
    inputs: dict[str, Path] = {}
    for path in [*found, *named]:
        for place in _places(path):
            inputs.setdefault(place, path)
    for output in combined_paths(folder).values():
        for place in _places(output):
            if place in inputs:
                raise ConfigError(
                    f"--output {folder}: {output.name} would overwrite the input "
                    f"{inputs[place]}; choose another --output folder"
                )


def _places(path: Path) -> set[str]:
    """Where ``path`` is: the file it resolves to, and the name in its resolved folder."""
    return {os.path.realpath(path), os.path.join(os.path.realpath(path.parent), path.name)}


@dataclass
class _Progress:
    """How far a run got, for the line an interrupt prints.

    Attributes:
        folder: The output folder, once known.
        files: The rendered files, once rendered (``files.written``: renamed in).
    """

    folder: Path | None = None
    files: CombinedFiles | None = None


def run(argv: list[str] | None = None) -> int:
    """Run ``rtaw-results`` with ``argv``; returns the exit status.

    Ctrl-C or SIGTERM prints one ``interrupted:`` line saying whether the combined files
    were written (all of them) or not (none changed), and returns 130 or 143.

    Raises:
        RtawError: No results found, a file that is not an ``rtaw-eval`` result, a
            metric not held by every result, an ``--x`` that is not swept, jobs of one
            setting that disagree, an output that is one of the inputs, an output
            folder in use, or an unknown baseline.
    """
    args = parser().parse_args(argv)
    progress = _Progress()
    with terminate_as_interrupt():
        try:
            return _combine(args, progress)
        except KeyboardInterrupt as exc:
            return _interrupted(exc, progress)


def _combine(args: argparse.Namespace, progress: _Progress) -> int:
    """The work of :func:`run`, recording in ``progress`` how far it got."""
    found = find_results(args.paths)
    progress.folder = _output(args)
    # Before anything is read: the outputs must not replace an input.
    _check_not_inputs(progress.folder, found, [p for p in args.paths if not p.is_dir()])
    # Every input is checked in full before the output folder is made or held.
    jobs = load_jobs(found)
    check_metric(jobs, args.metric)
    with claim_folder(progress.folder, "--output") as folder:
        evaluated = evaluated_policies(jobs)
        if args.reference is not None and args.reference not in evaluated:
            raise ConfigError(
                f"--reference {args.reference} was evaluated in no job; evaluated: "
                f"{', '.join(evaluated)}"
            )
        combined = combine(jobs, args.reference or REFERENCE, args.compare_to, metric=args.metric)
        table = combined_table(combined)
        progress.files = render_combined(folder, combined, table, x=args.x)
        print(table)
        written = progress.files.write()
    print(f"combined {len(jobs)} results files: {', '.join(map(str, written.values()))}")
    failed = sorted(p for path in args.paths if path.is_dir() for p in path.rglob("FAILED"))
    if failed:
        print(f"note: {len(failed)} failed jobs have no results: {failed[0]} ...", file=sys.stderr)
    return 0


def _interrupted(exc: KeyboardInterrupt, progress: _Progress) -> int:
    """Print the one line of a stop (what was written) and return ``128 + signal``."""
    signum = exc.signum if isinstance(exc, Interrupted) else signal.SIGINT
    if progress.files is not None and progress.files.written:
        kept = f"{OUTPUTS} were all written to {progress.folder}"
    elif progress.folder is not None:
        kept = f"nothing written; any {OUTPUTS} in {progress.folder} are as they were"
    else:
        kept = "nothing written"
    print(f"interrupted: {kept}", file=sys.stderr)
    return Interrupted(signum=signum).exit_status


def main(argv: list[str] | None = None) -> None:
    """Console entry point: user errors are one ``error:`` line and exit status 2; Ctrl-C
    and SIGTERM one ``interrupted:`` line and 130 or 143."""
    exit_after(run, argv)


if __name__ == "__main__":
    main()
