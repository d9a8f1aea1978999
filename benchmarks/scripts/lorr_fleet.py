"""A LoRR problem with fewer robots: the same map, tasks and reveal factor, the first
``M`` start cells (LoRR reads the first ``teamSize`` of its agent file).

Usage::

    python -m benchmarks.scripts.lorr_fleet PROBLEM.json M OUT_FOLDER

Writes ``OUT_FOLDER/<map stem>_<M>.json`` beside copies of the map, agent and task files
(LoRR resolves them relative to the problem), and prints its path. The start kit ships
``warehouse_large`` with 5,000 robots only; the 1,000-robot calibration runs on this.
"""

from __future__ import annotations

import argparse
import json
import shutil
from pathlib import Path

from rtaw_marl.sim.lorr import read_problem


def write_fleet(problem: Path, robots: int, out: Path) -> Path:
    """The problem with ``teamSize = robots`` written into ``out`` (made here)."""
    source = read_problem(str(problem))
    if not 1 <= robots <= source.team_size:
        raise SystemExit(f"M must be in 1..{source.team_size}, got {robots}")
    data = json.loads(source.path.read_text())
    out.mkdir(parents=True, exist_ok=False)
    for key in ("mapFile", "agentFile", "taskFile"):
        target = out / data[key]
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(source.path.parent / data[key], target)
    data["teamSize"] = robots
    path = out / f"{Path(data['mapFile']).stem}_{robots}.json"
    path.write_text(json.dumps(data, indent=4) + "\n")
    return path


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("problem", type=Path)
    parser.add_argument("robots", type=int)
    parser.add_argument("out", type=Path)
    args = parser.parse_args()
    print(write_fleet(args.problem, args.robots, args.out))


if __name__ == "__main__":
    main()
