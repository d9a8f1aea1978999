"""The throughput table of docs/results.md from ``rtaw-eval scenario=lorr`` results.

Usage::

    python -m benchmarks.scripts.throughput_table benchmarks/data/throughput/*.json
    python -m benchmarks.scripts.throughput_table --write docs/results.md benchmarks/data/throughput/*.json

Each file is an ``rtaw-eval`` ``results.json`` of ``horizon`` episodes (its setting
label: the problem's map and the robots; several files of one setting and seeds, with
other policies, are merged); prints the markdown table with LoRR 2024's
published figures beside the ``warehouse_large`` rows; ``--write`` replaces the
``throughput`` section of a markdown file (between its BEGIN and END markers).
"""

from __future__ import annotations

import argparse
import re
from pathlib import Path

from rtaw_marl.evaluation.results_file import read_results
from rtaw_marl.evaluation.throughput import throughput_markdown


def _label(payload: dict) -> str:
    sim, problem = payload["config"]["sim"], Path(payload["config"]["tasks"]["problem"])
    name = "warehouse_large" if "warehouse_large" in problem.name else problem.stem
    return f"{name}, M={int(sim['num_robots']):,}, T={int(sim['horizon']):,}"


def _payload(path: Path) -> dict:
    """A results file, read and checked by the package's one reader (an older file's
    ``config.env`` and ``rtaw:`` labels under today's names)."""
    results = read_results(path)
    return {"config": results.config, "seeds": results.seeds, "policies": results.policies}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("results", nargs="+", type=Path)
    parser.add_argument("--write", type=Path, help="markdown file whose section to replace")
    args = parser.parse_args()
    merged: dict[str, dict] = {}
    for path in args.results:
        payload = _payload(path)
        label = _label(payload)
        if label not in merged:
            merged[label] = payload
            continue
        # Several rtaw-eval runs of one setting (other policies): one row group.
        first = merged[label]
        if first["config"]["sim"] != payload["config"]["sim"] or first["seeds"] != payload["seeds"]:
            raise SystemExit(f"{path}: not the setting and seeds of the other {label} results")
        twice = set(first["policies"]) & set(payload["policies"])
        if twice:
            raise SystemExit(f"{path}: {sorted(twice)[0]} is evaluated twice for {label}")
        first["policies"] = {**first["policies"], **payload["policies"]}
    order = sorted(
        merged, key=lambda k: ("warehouse" in k, merged[k]["config"]["sim"]["num_robots"])
    )
    table = throughput_markdown([(k, merged[k]) for k in order])
    if args.write is None:
        print(table)
        return
    text = args.write.read_text()
    pattern = r"(<!-- BEGIN throughput -->\n).*?(<!-- END throughput -->)"
    if not re.search(pattern, text, flags=re.S):
        raise SystemExit(f"{args.write}: no <!-- BEGIN throughput --> section")
    args.write.write_text(re.sub(pattern, lambda m: m[1] + table + "\n" + m[2], text, flags=re.S))
    print(f"rewrote the throughput section of {args.write}")


if __name__ == "__main__":
    main()
