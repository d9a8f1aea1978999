"""Run one study of the project's results pages and print its tables.

Examples (from the repository root)::

    python -m benchmarks.run transfer --workers 2
    python -m benchmarks.run table1_paper --seeds 0 1 2 --output runs/t1
    python -m benchmarks.run table1_paper --output runs/t1 --resume     # after a kill
    python -m benchmarks.run table1_paper --reuse --write --workers 2   # docs/results.md

The tables go to stdout and are saved as ``<study>.txt`` beside ``<study>.json`` in the
run folder; progress lines go to stderr. ``--reuse`` takes the rules' per-seed TTDs from
``benchmarks/data/<study>.json``; ``--write`` stores the result there and rewrites the
study's section of its page in ``docs/``. Bad arguments: one ``error:`` line, exit 2.
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Sequence
from pathlib import Path

from benchmarks.studies import STUDIES
from benchmarks.studies import study as find_study
from benchmarks.study import StudyResult, load_result, replace_section, run_study, save_result
from rtaw_marl.errors import ConfigError, RtawError
from rtaw_marl.evaluation.transcript import Transcript, transcript_path
from rtaw_marl.sim.inputs import seed_list
from rtaw_marl.utils.runs import claim_file

ROOT = Path(__file__).resolve().parents[1]
#: The stored per-seed results the pages are rendered from.
DATA = ROOT / "benchmarks" / "data"
DOCS = ROOT / "docs"


def parse(argv: Sequence[str] | None = None) -> argparse.Namespace:
    """The command line, checked: a bad value exits 2 with one ``error:`` line."""
    parser = argparse.ArgumentParser(prog="python -m benchmarks.run", description=__doc__)
    parser.add_argument("study", help=f"one of: {', '.join(STUDIES)}")
    parser.add_argument("--seeds", type=int, nargs="+", help="default: the study's own")
    parser.add_argument("--workers", type=int, default=1, help="evaluation processes")
    parser.add_argument("--output", type=Path, help="run folder (default: runs/study/<name>)")
    parser.add_argument("--resume", action="store_true", help="take journalled episodes")
    parser.add_argument("--data", type=Path, default=DATA, help="stored results folder")
    parser.add_argument("--docs", type=Path, default=DOCS, help="the pages --write rewrites")
    parser.add_argument("--reuse", action="store_true", help="the rules' stored TTDs")
    parser.add_argument(
        "--reuse-learned",
        action="store_true",
        help="with --reuse, the learned policies' stored TTDs too (only missing labels run)",
    )
    parser.add_argument("--write", action="store_true", help="store and rewrite the page")
    args = parser.parse_args(argv)
    try:
        find_study(args.study)
        if args.workers < 1:
            raise ConfigError(f"--workers must be at least 1, got {args.workers}")
        if args.seeds is not None:
            seed_list(args.seeds, "--seeds")
        if args.reuse_learned and not args.reuse:
            raise ConfigError("--reuse-learned needs --reuse")
    except ConfigError as err:
        parser.error(str(err))
    return args


def run(args: argparse.Namespace) -> StudyResult:
    """Run ``args.study``; print its tables and write them where asked."""
    study = find_study(args.study)
    seeds = list(study.default_seeds if args.seeds is None else args.seeds)
    stored = {name: _stored(args.data, name, args.study) for name in study.pairs_with}
    if args.write and study.page is not None and not (args.docs / study.page).is_file():
        raise ConfigError(f"--write: {args.docs / study.page} does not exist")
    output = args.output or Path("runs", "study", f"{study.name}-{time.strftime('%Y%m%d-%H%M%S')}")
    with claim_file(output / f"{study.name}.json") as path:
        reuse = load_result(args.data / f"{study.name}.json") if args.reuse else None
        result = run_study(
            study, seeds, output, args.workers, args.resume, reuse, args.reuse_learned
        )
        save_result(path, result)
    body = study.render(result, stored)
    report = Transcript()
    report.print(body)
    report.print(f"results: {path}")
    if args.write:
        if study.store:
            save_result(args.data / f"{study.name}.json", result)
        if study.page is not None:
            replace_section(args.docs / study.page, study.name, body)
            report.print(f"rewrote the {study.name} section of {args.docs / study.page}")
    report.save(transcript_path(path))
    return result


def _stored(data: Path, name: str, study: str) -> StudyResult:
    """A stored result that ``study``'s tables pair with."""
    result = load_result(data / f"{name}.json")
    if result is None:
        raise ConfigError(f"{study} needs {data / f'{name}.json'}: run the study {name} first")
    return result


def main(argv: Sequence[str] | None = None) -> None:
    """Parse, run; a user's error is one line on stderr and exit status 2."""
    args = parse(argv)
    try:
        run(args)
    except RtawError as err:
        print(f"error: {err}", file=sys.stderr)
        sys.exit(2)


if __name__ == "__main__":
    main()
