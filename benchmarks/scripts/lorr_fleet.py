"""A LoRR problem with another fleet size: the same map, tasks and reveal factor; the
first ``M`` start cells of its agent file (LoRR reads the first ``teamSize``), and for
more robots than the file holds, distinct free cells drawn at random (seed 0) after them.

Usage::

    python -m benchmarks.scripts.lorr_fleet PROBLEM.json M OUT_FOLDER

Writes ``OUT_FOLDER/<map stem>_<M>.json`` beside copies of the map, agent and task files
(LoRR resolves them relative to the problem), and prints its path. The start kit ships
``warehouse_large`` with 5,000 robots only; the 1,000- and 10,000-robot runs use this
(the own simulator draws its extra starts differently: ``tasks.starts=random``).
"""

from __future__ import annotations

import argparse
import json
import shutil
from pathlib import Path

import numpy as np

from rtaw_marl.sim.lorr import read_agents, read_problem


def write_fleet(problem: Path, robots: int, out: Path) -> Path:
    """The problem with ``teamSize = robots`` written into ``out`` (made here)."""
    source = read_problem(str(problem))
    layout = source.layout()
    if not 1 <= robots <= int((~layout.obstacles).sum()):
        free_cells = int((~layout.obstacles).sum())
        raise SystemExit(f"M must be in 1..{free_cells} (free cells), got {robots}")
    data = json.loads(source.path.read_text())
    out.mkdir(parents=True, exist_ok=False)
    for key in ("mapFile", "agentFile", "taskFile"):
        target = out / data[key]
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(source.path.parent / data[key], target)
    xy = read_agents(source.agents_path, layout)
    agents = xy[:, 1] * layout.width + xy[:, 0]  # LoRR's linearized cells
    if robots > len(agents):
        free = np.flatnonzero(~layout.obstacles.ravel())
        rest = np.setdiff1d(free, agents)
        extra = np.random.default_rng(0).choice(rest, robots - len(agents), replace=False)
        cells = np.concatenate([agents, extra])
        data["agentFile"] = f"agents/{Path(data['mapFile']).stem}_{robots}.agents"
        lines = ["# version for LoRR 2024", str(robots), *map(str, cells.tolist())]
        (out / data["agentFile"]).write_text("\n".join(lines) + "\n")
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
