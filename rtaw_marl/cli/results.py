"""``rtaw-results``: combine a sweep's ``results.json`` files into one table and one plot.

Examples::

    rtaw-results multirun/eval/2026-12-04/12-00-00_123      # every job of one sweep
    rtaw-results multirun/eval/2026-12-04 runs/big/results.json --output combined/
    rtaw-results SWEEP --reference lookahead --compare-to rbts

Every ``results.json`` under the folders given (and every file named) is read; rows
are grouped by setting, named by the overrides that differ between jobs (a sweep over
``policy`` merges into one setting). The table (mean TTD with its 95% interval, the
paired difference with MPDM or ``--reference``, as ``rtaw-eval`` prints them) goes to
stdout and, with a CSV, a JSON and a PNG plot, into ``<output>/combined.*`` (default:
the one folder given). No results found, an unreadable or foreign file, or two jobs of
one setting that disagree: one ``error:`` line, exit status 2.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from rtaw_marl.cli.plain import OneLineParser, exit_after
from rtaw_marl.errors import ConfigError
from rtaw_marl.evaluation.combine import combine, evaluated_policies, load_jobs
from rtaw_marl.evaluation.combine_output import combined_table, write_combined
from rtaw_marl.utils.runs import check_writable_dir

__all__ = ["main", "parser", "run"]

#: rtaw-eval's main baseline.
REFERENCE = "mpdm"


def parser() -> argparse.ArgumentParser:
    """The command line of ``rtaw-results``."""
    p = OneLineParser(prog="rtaw-results", description=__doc__.splitlines()[0])
    p.add_argument("paths", nargs="+", type=Path, help="sweep folders or results.json files")
    p.add_argument(
        "--output", type=Path,
        help="folder of combined.{txt,csv,json,png} (default: the one folder given)",
    )  # fmt: skip
    p.add_argument(
        "--reference", help=f"the main baseline of the comparisons (default: {REFERENCE})"
    )
    p.add_argument("--compare-to", help="a second baseline, as rtaw-eval's compare_to")
    return p


def _output(args: argparse.Namespace) -> Path:
    if args.output is not None:
        return args.output
    if len(args.paths) == 1 and args.paths[0].is_dir():
        return args.paths[0]
    raise ConfigError("give --output FOLDER when combining files or several folders")


def run(argv: list[str] | None = None) -> int:
    """Run ``rtaw-results`` with ``argv``; returns the exit status.

    Raises:
        RtawError: No results found, a file that is not an ``rtaw-eval`` result, jobs
            of one setting that disagree, or an unknown baseline.
    """
    args = parser().parse_args(argv)
    jobs = load_jobs(args.paths)
    folder = check_writable_dir(_output(args), "--output")
    evaluated = evaluated_policies(jobs)
    if args.reference is not None and args.reference not in evaluated:
        raise ConfigError(
            f"--reference {args.reference} was evaluated in no job; evaluated: "
            f"{', '.join(evaluated)}"
        )
    combined = combine(jobs, args.reference or REFERENCE, args.compare_to)
    table = combined_table(combined)
    print(table)
    written = write_combined(folder, combined, table)
    print(f"combined {len(jobs)} results files: {', '.join(map(str, written.values()))}")
    failed = sorted(p for path in args.paths if path.is_dir() for p in path.rglob("FAILED"))
    if failed:
        print(f"note: {len(failed)} failed jobs have no results: {failed[0]} ...", file=sys.stderr)
    return 0


def main(argv: list[str] | None = None) -> None:
    """Console entry point: user errors are one ``error:`` line and exit status 2."""
    exit_after(run, argv)


if __name__ == "__main__":
    main()
