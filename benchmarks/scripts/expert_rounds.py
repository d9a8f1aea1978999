"""Does a round of expert iteration pay? Networks compared on selection seeds.

Usage::

    python -m benchmarks.scripts.expert_rounds generalist_plus runs/expert/round1/checkpoints/best.pt
    python -m benchmarks.scripts.expert_rounds A B --width 2 --horizon 3 --seeds 10
    python -m benchmarks.scripts.expert_rounds A B --settings C_astar_m10:n15 A_astar_m10:s80:random

Each policy (a checkpoint or shipped name) plays alone and searched
(``load_search(width, horizon)``) on the settings of
:mod:`benchmarks.scripts.search_defaults` (or ``--settings``: mix members) over the
selection seeds 1000.. (never an
evaluation seed), beside the best rule there (least mean TTD among
:data:`~rtaw_marl.evaluation.best_rule.DEFAULT_RULES` on the same seeds: a bar for the
eye, not a selection). Prints each one's pooled paired TTD difference against the first
policy alone (positive: better), and against the best rule. A round pays when its
network (or its search) is ahead of the previous round's on these seeds.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from benchmarks.scripts.search_defaults import SETTINGS
from rtaw_marl.evaluation import evaluate
from rtaw_marl.evaluation.best_rule import DEFAULT_RULES
from rtaw_marl.evaluation.stats import pooled_difference
from rtaw_marl.policies import load_policy, make_baseline
from rtaw_marl.policies.search_policy import load_search
from rtaw_marl.scenarios.mix import member_spec
from rtaw_marl.sim.builder import build_sim
from rtaw_marl.utils.atomic import atomic_write


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("policies", nargs="+")
    parser.add_argument("--width", type=int, default=2)
    parser.add_argument("--horizon", type=int, default=3)
    parser.add_argument("--seeds", type=int, default=10)
    parser.add_argument("--output", type=Path, default=None)
    parser.add_argument("--settings", nargs="+", default=list(SETTINGS), help="mix members")
    args = parser.parse_args()
    seeds = list(range(1000, 1000 + args.seeds))
    ttd: dict[str, dict[str, list[float]]] = {}
    for setting in args.settings:
        sim = build_sim(member_spec(setting))
        policies = {r: make_baseline(r) for r in DEFAULT_RULES}
        for i, source in enumerate(args.policies):
            policies[f"p{i}"] = load_policy(source)
            policies[f"p{i}+search"] = load_search(source, width=args.width, horizon=args.horizon)
        results = evaluate(sim, policies, seeds)
        ttd[setting] = {name: r["ttd"] for name, r in results.items()}
        best = min(DEFAULT_RULES, key=lambda r: np.mean(ttd[setting][r]))
        ttd[setting]["best rule"] = ttd[setting][best]
        print(f"{setting}: best rule {best}", flush=True)
    for i, source in enumerate(args.policies):
        for name in (f"p{i}", f"p{i}+search"):
            vs_first = pooled_difference([(t["p0"], t[name]) for t in ttd.values()])
            vs_rule = pooled_difference([(t["best rule"], t[name]) for t in ttd.values()])
            assert vs_first is not None
            assert vs_rule is not None
            print(
                f"{name:10s} {source}: vs p0 {vs_first.mean:+.2f}% [{vs_first.low:+.2f}, "
                f"{vs_first.high:+.2f}]; vs best rule {vs_rule.mean:+.2f}% "
                f"[{vs_rule.low:+.2f}, {vs_rule.high:+.2f}]"
            )
    if args.output is not None:
        text = json.dumps({"policies": args.policies, "seeds": seeds, "ttd": ttd}, indent=1)
        atomic_write(args.output, lambda f: f.write(text.encode()))


if __name__ == "__main__":
    main()
