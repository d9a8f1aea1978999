"""The official-judge table of docs/results.md: ``rtaw-lorr`` results beside ``rtaw-eval``.

Usage::

    python -m benchmarks.scripts.lorr_table benchmarks/data/lorr/NAME_t500.json:benchmarks/data/lorr/NAME_t500_own.json
    python -m benchmarks.scripts.lorr_table --write docs/results.md OFFICIAL.json:OWN.json ...

Each argument is an ``rtaw-lorr`` results file, optionally ``:`` an ``rtaw-eval`` results
file (or several joined by ``+``: same seeds, other policies) of the same problem and
horizon (``scenario=lorr sim.horizon=T``); ``--write``
replaces the ``lorr`` section of a markdown file (between its BEGIN and END markers).
"""

from __future__ import annotations

import argparse
import json
import re
from pathlib import Path

from benchmarks.lorr_judge import judge_markdown
from rtaw_marl.evaluation.results_file import read_results


def _section(pair: str) -> str:
    official_path, _, own_paths = pair.partition(":")
    official = json.loads(Path(official_path).read_text())
    own = _merged(own_paths.split("+")) if own_paths else None
    own_path = own_paths
    if own is not None and int(own["config"]["sim"]["horizon"]) != int(
        official["config"]["timesteps"]
    ):
        raise SystemExit(f"{own_path}: not the horizon of {official_path}")
    first = next(iter(official["runs"].values()))
    title = f"**{Path(official['problem']).stem}**, {first['team_size']:,} robots"
    return f"{title}\n\n{judge_markdown(official, own)}\n"


def _merged(paths: list[str]) -> dict:
    """Several rtaw-eval results of one setting and seeds (other policies), as one
    (read by the package's one reader: an older file's ``config.env`` is ``config.sim``)."""
    first = _payload(paths[0])
    for path in paths[1:]:
        other = _payload(path)
        if other["config"]["sim"] != first["config"]["sim"] or other["seeds"] != first["seeds"]:
            raise SystemExit(f"{path}: not the setting and seeds of {paths[0]}")
        first["policies"] = {**first["policies"], **other["policies"]}
    return first


def _payload(path: str) -> dict:
    results = read_results(path)
    return {"config": results.config, "seeds": results.seeds, "policies": results.policies}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("pairs", nargs="+", help="OFFICIAL.json[:OWN.json[+OWN2.json]]")
    parser.add_argument("--write", type=Path, help="markdown file whose section to replace")
    args = parser.parse_args()
    table = "\n".join(_section(p) for p in args.pairs)
    if args.write is None:
        print(table)
        return
    text = args.write.read_text()
    pattern = r"(<!-- BEGIN lorr -->\n).*?(<!-- END lorr -->)"
    if not re.search(pattern, text, flags=re.S):
        raise SystemExit(f"{args.write}: no <!-- BEGIN lorr --> ... <!-- END lorr --> section")
    args.write.write_text(re.sub(pattern, lambda m: m[1] + table + m[2], text, flags=re.S))
    print(f"wrote {args.write}")


if __name__ == "__main__":
    main()
