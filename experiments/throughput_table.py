"""The throughput table of docs/results.md from ``rtaw-eval scenario=lorr`` results.

Usage::

    python experiments/throughput_table.py docs/data/throughput/*.json

Each file is an ``rtaw-eval`` ``results.json`` of ``horizon`` episodes (its setting
label: the problem's map and the robots); prints the markdown table with LoRR 2024's
published figures beside the ``warehouse_large`` rows.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from rtaw_marl.evaluation.throughput import throughput_markdown


def _label(payload: dict) -> str:
    env, problem = payload["config"]["env"], Path(payload["config"]["tasks"]["problem"])
    name = "warehouse_large" if "warehouse_large" in problem.name else problem.stem
    return f"{name}, M={int(env['num_robots']):,}, T={int(env['horizon']):,}"


def main() -> None:
    payloads = [json.loads(Path(p).read_text()) for p in sys.argv[1:]]
    payloads.sort(key=lambda p: ("warehouse" in _label(p), p["config"]["env"]["num_robots"]))
    print(throughput_markdown([(_label(p), p) for p in payloads]))


if __name__ == "__main__":
    main()
