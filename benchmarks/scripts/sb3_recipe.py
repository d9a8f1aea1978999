"""SB3-contrib's MaskablePPO on the Gymnasium adapter, with the recipe that learns.

Usage::

    python -m benchmarks.scripts.sb3_recipe                         # the documented run
    python -m benchmarks.scripts.sb3_recipe --set gamma=0.99 scale_reward=False   # SB3's defaults
    python -m benchmarks.scripts.sb3_recipe --steps 8192 --json /tmp/r.json --plot /tmp/c.png

Trains ``MaskablePPO`` with :data:`benchmarks.sb3.RECIPE` (``--set`` changes
a setting) on 10 robots, 100 tasks, the default layout and navigator, on training seeds
only; every ``--every`` decisions it plays the greedy policy on 10 selection seeds
(1000-1009) for the learning curve. Then it plays the trained policy, MPDM and random on
the evaluation seeds 0-19 and prints the paired differences with their 95% intervals.
Writes the numbers and per-seed TTDs to ``--json`` (benchmarks/data/sb3_recipe.json) and the
curve to ``--plot`` (docs/img/sb3_curve.png). One torch thread.
"""

from __future__ import annotations

import argparse
import ast
import io
import json
import sys
import time
from pathlib import Path
from typing import Any

import torch
from stable_baselines3.common.callbacks import BaseCallback

from benchmarks.sb3 import RECIPE, evaluate_model, make_model, rule_ttds
from rtaw_marl.errors import ConfigError
from rtaw_marl.evaluation.stats import paired_difference
from rtaw_marl.sim.inputs import SELECTION_SEEDS
from rtaw_marl.utils.atomic import atomic_write

ROOT = Path(__file__).resolve().parents[2]
SCENARIO: dict[str, Any] = {"num_robots": 10, "num_tasks": 100}
EVAL_SEEDS = list(range(20))
CURVE_SEEDS = list(range(SELECTION_SEEDS, SELECTION_SEEDS + 10))
RULES = ("random", "mpdm")


class Curve(BaseCallback):
    """Every ``every`` decisions, the greedy policy's mean TTD on the curve seeds; and the
    TTD of every training episode (the sampling policy, on training seeds)."""

    def __init__(self, every: int) -> None:
        super().__init__()
        self.every = every
        self.greedy: list[tuple[int, float]] = []
        self.episodes: list[tuple[int, float]] = []

    def _on_training_start(self) -> None:
        self._record()  # the untrained policy: where the curve starts

    def _on_rollout_start(self) -> None:
        # Called after each update: the greedy point shows the policy just trained.
        if self.num_timesteps - self.greedy[-1][0] >= self.every:
            self._record()

    def _on_step(self) -> bool:
        for done, info in zip(self.locals["dones"], self.locals["infos"], strict=True):
            if done:
                self.episodes.append((self.num_timesteps, float(info["ttd"])))
        return True

    def _on_training_end(self) -> None:
        if self.greedy[-1][0] != self.num_timesteps:
            self._record()

    def _record(self) -> None:
        ttds = evaluate_model(self.model, SCENARIO, CURVE_SEEDS)
        self.greedy.append((self.num_timesteps, sum(ttds) / len(ttds)))


def plot(curve: Curve, rules: dict[str, list[float]], path: Path) -> None:
    """The learning curve, with the rules' mean TTD on the same curve seeds."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.5, 3.8), dpi=120)
    if curve.episodes:  # none when the run is shorter than an episode
        steps, ttd = zip(*curve.episodes, strict=True)
        ax.plot(steps, ttd, ".", color="tab:gray", alpha=0.3, ms=3, label="training episodes")
    steps, ttd = zip(*curve.greedy, strict=True)
    ax.plot(steps, ttd, marker="o", color="tab:blue", label="MaskablePPO (greedy)")
    for (name, ttds), style in zip(rules.items(), ("tab:orange", "tab:red"), strict=True):
        ax.axhline(sum(ttds) / len(ttds), color=style, linestyle="--", label=name)
    ax.set_xlabel("decisions (env steps)")
    ax.set_ylabel("episode TTD (s)")
    ax.set_title("MaskablePPO, 10 robots, 100 tasks\n(greedy and rules: selection seeds 1000-1009)")
    ax.legend(fontsize=8)
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format="png")
    plt.close(fig)
    atomic_write(path, lambda fh: fh.write(buf.getvalue()))


def parse_settings(pairs: list[str]) -> dict[str, Any]:
    """``key=value`` pairs (Python literals) to recipe overrides."""
    settings = {}
    for pair in pairs:
        key, sep, value = pair.partition("=")
        if not sep:
            raise ConfigError(f"--set takes key=value, got {pair!r}")
        try:
            settings[key] = ast.literal_eval(value)
        except (ValueError, SyntaxError):
            raise ConfigError(f"--set {key}: {value!r} is not a Python literal") from None
    return settings


def run(args: argparse.Namespace) -> dict[str, Any]:
    """Train, draw the curve, evaluate; returns the numbers written to ``--json``."""
    if args.steps < 1 or args.every < 1:
        raise ConfigError(f"--steps and --every must be >= 1, got {args.steps} and {args.every}")
    recipe = RECIPE.with_overrides(**parse_settings(args.set))
    model = make_model(SCENARIO, recipe, seed=args.seed)
    curve = Curve(args.every)
    start = time.perf_counter()
    model.learn(args.steps, callback=curve)
    wall = time.perf_counter() - start
    plot(curve, {rule: rule_ttds(rule, SCENARIO, CURVE_SEEDS) for rule in RULES}, args.plot)
    ttds = {"maskable_ppo": evaluate_model(model, SCENARIO, EVAL_SEEDS)}
    ttds |= {rule: rule_ttds(rule, SCENARIO, EVAL_SEEDS) for rule in RULES}
    return {
        "scenario": SCENARIO,
        "recipe": recipe.ppo_kwargs() | {"scale_reward": recipe.scale_reward},
        "steps": args.steps,
        "seed": args.seed,
        "train_wall_s": round(wall, 1),
        "eval_seeds": EVAL_SEEDS,
        "ttd": ttds,
        "vs": {
            rule: paired_difference(ttds[rule], ttds["maskable_ppo"]).as_dict() for rule in RULES
        },
        "curve": {"greedy": curve.greedy, "curve_seeds": CURVE_SEEDS},
    }


def report(result: dict[str, Any]) -> str:
    """The run in a few lines: mean TTDs and the paired differences."""
    lines = [f"trained {result['steps']} decisions in {result['train_wall_s']} s"]
    for name, ttds in result["ttd"].items():
        lines.append(f"{name:>13}: mean TTD {sum(ttds) / len(ttds):8.1f} (seeds 0-19)")
    for rule, diff in result["vs"].items():
        low, high = diff["pct_ci"]
        lines.append(
            f"MaskablePPO vs {rule}: {-diff['pct']:+.1f}% [{-high:+.1f}, {-low:+.1f}] "
            "(paired 95% interval; negative: MaskablePPO lower)"
        )
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=65536, help="training decisions")
    parser.add_argument("--seed", type=int, default=0, help="training seed (>= 0)")
    parser.add_argument("--every", type=int, default=4096, help="curve point every N steps")
    parser.add_argument("--set", nargs="*", default=[], help="recipe overrides key=value")
    parser.add_argument(
        "--json", type=Path, default=ROOT / "benchmarks" / "data" / "sb3_recipe.json"
    )
    parser.add_argument("--plot", type=Path, default=ROOT / "docs" / "img" / "sb3_curve.png")
    args = parser.parse_args(argv)
    torch.set_num_threads(1)  # a small MLP: more threads only contend
    try:
        result = run(args)
    except ConfigError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    text = json.dumps(result, indent=1).encode()
    atomic_write(args.json, lambda fh: fh.write(text))
    print(report(result))
    return 0


if __name__ == "__main__":
    sys.exit(main())
