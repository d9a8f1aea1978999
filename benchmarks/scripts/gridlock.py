"""Does lifelong PIBT gridlock at LoRR's scale? Tasks finished per window over a long run.

Usage::

    python -m benchmarks.scripts.gridlock                              # turns, guidance 1
    python -m benchmarks.scripts.gridlock --guidance 0 --horizon 5000  # without guidance
    python -m benchmarks.scripts.gridlock --policy pair_greedy         # the 2024 winner's rule
    python -m benchmarks.scripts.gridlock --matched lorr_warehouse_plus  # a network, batched

LoRR's ``warehouse_large`` with 10,000 robots (the first 5,000 start cells of its agent
file, random distinct cells beyond; its task file and reveal window), MPDM (or another
rule, or a learned policy deciding each timestep's robots together with ``candidates=32``:
``--matched NAME``), one core.
Prints the tasks finished per 500 timesteps, the best 1,000-timestep window (sliding by
100) and the last one, their ratio (gridlock: the last window far below the best), the
longest any robot waited for its goal to change (``max_stall``) and the wall time. With
``--output``, the same as JSON.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from benchmarks.scripts.bench_pibt import PROBLEM
from rtaw_marl.policies import make_baseline
from rtaw_marl.policies.base import Policy
from rtaw_marl.scenarios import lorr_scenario
from rtaw_marl.sim.builder import build_sim
from rtaw_marl.utils.atomic import atomic_write

#: Bins of the per-window counts, and the window of the gridlock ratio.
BIN, WINDOW = 100, 1000


def run(
    robots: int, horizon: int, turns: bool, guidance: float, policy: str,
    guide_replans: int = 0, patience: int | None = None,
) -> dict:  # fmt: skip
    """One episode; its tasks finished per :data:`BIN` timesteps and the windows."""
    nav = {
        "name": "pibt", "record": False, "turns": turns, "guidance": guidance,
        "guide_replans": guide_replans, "patience": patience,
    }  # fmt: skip
    starts = "file" if robots <= 5000 else "random"
    scenario = lorr_scenario(PROBLEM, num_robots=robots, horizon=horizon, starts=starts,
                             navigator=nav)  # fmt: skip
    sim = build_sim(scenario.spec())
    rule = _policy(policy)
    sim.reset(0)
    began = time.perf_counter()
    while not sim.done:
        sim.step(rule.act_sim(sim))
    served = sim.task_finished[sim.task_robot >= 0]
    done = served[np.isfinite(served) & (served <= horizon)]
    per = np.histogram(done, bins=np.arange(0, horizon + BIN, BIN))[0][: horizon // BIN]
    windows = np.convolve(per, np.ones(WINDOW // BIN, dtype=np.int64), "valid")
    return {
        "robots": robots, "horizon": horizon, "turns": turns, "guidance": guidance,
        "guide_replans": guide_replans, "patience": patience, "policy": policy, "finished": len(done), "per_bin": per.tolist(),
        "best_window": int(windows.max()), "last_window": int(windows[-1]),
        "ratio": float(windows[-1] / max(1, windows.max())),
        "max_stall": float(sim.executor.stats()["max_stall"]),
        "wall_s": time.perf_counter() - began,
    }  # fmt: skip


def _policy(name: str) -> Policy:
    """A rule by name, or ``matched:NAME``: a learned policy deciding in batches."""
    if not name.startswith("matched:"):
        return make_baseline(name)
    import torch

    from rtaw_marl.policies.matched import MatchedPolicy
    from rtaw_marl.policies.network import load_policy

    torch.set_num_threads(1)
    return MatchedPolicy(load_policy(name.split(":", 1)[1], candidates=32))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robots", type=int, default=10_000)
    parser.add_argument("--horizon", type=int, default=5000)
    parser.add_argument("--no-turns", dest="turns", action="store_false")
    parser.add_argument("--guidance", type=float, default=1.0)
    parser.add_argument("--guide-replans", type=int, default=0)
    parser.add_argument("--patience", type=int, default=None, help="priority rotation")
    parser.add_argument("--policy", default="mpdm")
    parser.add_argument("--matched", default=None, help="a learned policy, batched (k = 32)")
    parser.add_argument("--output", type=Path)
    args = parser.parse_args()
    if args.horizon < WINDOW or args.horizon % BIN:
        parser.error(f"--horizon must be a multiple of {BIN} and at least {WINDOW}")
    policy = args.policy if args.matched is None else f"matched:{args.matched}"
    r = run(
        args.robots, args.horizon, args.turns, args.guidance, policy,
        args.guide_replans, args.patience,
    )  # fmt: skip
    model = "turns" if r["turns"] else "no turns"
    print(f"{r['robots']:,} robots, {model}, guidance {r['guidance']:g} "
          f"(+{r['guide_replans']} re-planned a timestep), patience {r['patience']}, "
          f"{r['policy']}: "
          f"{r['finished']:,} tasks in {r['horizon']:,} timesteps ({r['wall_s']:.0f} s)")  # fmt: skip
    per500 = np.add.reduceat(np.array(r["per_bin"]), np.arange(0, len(r["per_bin"]), 5))
    print("per 500 timesteps:", ", ".join(f"{int(v):,}" for v in per500))
    print(f"best {WINDOW}-timestep window {r['best_window']:,}, last {r['last_window']:,} "
          f"(ratio {r['ratio']:.2f}); max_stall {r['max_stall']:.0f}")  # fmt: skip
    if args.output is not None:
        text = json.dumps(r, indent=1) + "\n"
        atomic_write(args.output, lambda f: f.write(text.encode()))


if __name__ == "__main__":
    main()
