"""BenchMARL's MAPPO on the default scenario: a learned baseline from another library.

Usage::

    python -m benchmarks.scripts.benchmarl_baseline train      # 409,600 frames -> runs/benchmarl
    python -m benchmarks.scripts.benchmarl_baseline train --frames 16384 --out /tmp/bm
    python -m benchmarks.scripts.benchmarl_baseline evaluate   # seeds 0-19 -> benchmarks/data/benchmarl.json

Needs ``benchmarl`` (``pip install --no-deps benchmarl==1.5.2``, docs/benchmarl.md).

``train`` runs BenchMARL's own ``Experiment`` with MAPPO and its MLP (actor and critic,
``conf/model/layers/mlp.yaml``: 256-256 tanh) on ``rtaw/warehouse``
(:mod:`rtaw_marl.integrations.benchmarl`; the default scenario: 60x60 shelves, A*,
designated tasks, 10 robots, 500 tasks, drain). BenchMARL's MAPPO defaults, except the
PPO settings that ``rtaw-train algo=ppo`` also has, which take its values: 8,192 frames
per batch (8 envs), 4 passes of 2,048-frame minibatches, lr 1e-3, gradient norm 0.5,
gamma 0.99, GAE lambda 0.95, entropy 0.005 (rtaw-train anneals 0.01 -> 0.001; BenchMARL
has no schedule). No warm start (BenchMARL has no imitation phase; RTAW+ had 65,536
labelled decisions before its 409,600 PPO frames). Like the shipped RTAW policies, the
greedy policy is evaluated on the selection seeds 1000-1009 every 81,920 frames (the RTAW
runs: every 40,960; half as often here, for the wall time) and the
best is kept (``best.pt``); ``final.pt`` is the last.

``evaluate`` plays the kept policy greedily on the PettingZoo env through the same
TorchRL wrapper, on the evaluation seeds 0-19 (``reset(seed=s)`` fixes the episode as
``rtaw-eval``'s ``sim.reset(s)`` does), plays MPDM through that same path and checks its
TTDs equal ``rtaw_marl.evaluation.evaluate``'s (what ``rtaw-eval policy=mpdm`` runs),
evaluates lookahead and the shipped RTAW+ there, and prints paired differences.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
import torch
from tensordict import TensorDictBase
from torchrl.envs import EnvBase
from torchrl.envs.utils import ExplorationType, set_exploration_type

# First: it lets BenchMARL 1.5.2 import under torchrl 0.14 (see its docstring).
from rtaw_marl.integrations.benchmarl import WarehouseTask, load_task_config

# isort: split
from benchmarl.algorithms import MappoConfig
from benchmarl.experiment import Callback, Experiment, ExperimentConfig
from benchmarl.models.mlp import MlpConfig

from rtaw_marl.evaluation import PairedDiff, evaluate, paired_difference, write_json_atomic
from rtaw_marl.policies import MPDM, make_baseline
from rtaw_marl.policies.network import load_policy
from rtaw_marl.policies.pretrained.registry import pretrained_path
from rtaw_marl.sim.builder import SimSpec, build_sim

ROOT = Path(__file__).resolve().parents[2]
EVAL_SEEDS = list(range(20))
SELECTION_SEEDS = list(range(1000, 1010))
SELECT_EVERY = 81_920
RTAW_PLUS = "shelves_astar_m10_plus"
GROUP = "agents"

Policy = Callable[[TensorDictBase], TensorDictBase]


def experiment(frames: int, out: Path, seed: int = 0, callbacks: tuple = ()) -> Experiment:
    """BenchMARL's MAPPO + MLP on ``rtaw/warehouse`` (the module docstring lists the settings)."""
    cfg = ExperimentConfig.get_from_yaml()
    cfg.max_n_frames = frames
    cfg.on_policy_collected_frames_per_batch = min(8192, frames)
    cfg.on_policy_n_envs_per_worker = 8
    cfg.on_policy_minibatch_size = min(2048, frames)
    cfg.on_policy_n_minibatch_iters = 4
    cfg.lr = 1e-3
    cfg.clip_grad_val = 0.5
    cfg.gamma = 0.99
    cfg.evaluation = False
    cfg.render = False
    cfg.loggers = ["csv"]
    cfg.create_json = False
    cfg.checkpoint_interval = 0
    cfg.checkpoint_at_end = False
    out.mkdir(parents=True, exist_ok=True)
    cfg.save_folder = str(out)
    algo = MappoConfig.get_from_yaml()
    algo.lmbda = 0.95
    algo.entropy_coef = 0.005
    return Experiment(
        task=WarehouseTask.WAREHOUSE.get_task(),
        algorithm_config=algo,
        model_config=MlpConfig.get_from_yaml(),
        critic_model_config=MlpConfig.get_from_yaml(),
        seed=seed,
        config=cfg,
        callbacks=list(callbacks),
    )


@torch.no_grad()
def play(env: EnvBase, policy: Policy, seed: int) -> dict[str, float]:
    """One greedy episode from ``reset(seed=seed)``: its metrics and nearest-task rate."""
    steps = int(load_task_config()["num_tasks"])
    with set_exploration_type(ExplorationType.DETERMINISTIC):
        rollout = env.rollout(
            steps, policy, tensordict=env.reset(seed=seed), auto_reset=False,
            break_when_any_done=True,
        )  # fmt: skip
    if not bool(rollout[-1]["next", "done"]):
        raise RuntimeError(f"seed {seed}: the episode did not end in {steps} steps")
    info = rollout[-1]["next", GROUP, "info"][0]
    row = {key: float(value) for key, value in info.items()}
    row["nearest_rate"] = nearest_rate(env, rollout)
    return row


def nearest_rate(env: EnvBase, rollout: TensorDictBase) -> float:
    """Share of decisions that took a nearest task (smallest distance ``k``)."""
    layout = env.base_env._env.unwrapped.obs_layout
    acting = rollout[GROUP, "mask"]
    obs = rollout[GROUP, "observation", "observation"][acting].numpy()
    k = layout.unflatten(obs)["tasks"][..., 4]
    valid = rollout[GROUP, "action_mask"][acting].numpy()
    chosen = rollout[GROUP, "action"][acting].numpy()
    k = np.where(valid, k, np.inf)
    picked = k[np.arange(len(k)), chosen]
    return float(np.mean(picked <= k.min(axis=1) + 1e-6))


class RulePolicy:
    """A rule of :mod:`rtaw_marl.policies` acting for the robot whose row is marked."""

    def __init__(self, env: EnvBase, rule: MPDM) -> None:
        self.layout = env.base_env._env.unwrapped.obs_layout
        self.rule = rule

    def __call__(self, td: TensorDictBase) -> TensorDictBase:
        acting = int(td[GROUP, "mask"].nonzero()[0, 0])
        features = self.layout.unflatten(td[GROUP, "observation", "observation"][acting].numpy())
        mask = td[GROUP, "action_mask"][acting].numpy().astype(np.int8)
        action = torch.zeros(td[GROUP, "mask"].shape, dtype=torch.long)
        action[acting] = self.rule.act({"observation": features, "action_mask": mask})
        td.set((GROUP, "action"), action)
        return td


class Selection(Callback):
    """Every ``SELECT_EVERY`` frames: greedy TTD on the selection seeds; keep the best."""

    def __init__(self, out: Path) -> None:
        super().__init__()
        self.out = out
        self.best = float("inf")
        self.log: list[dict[str, float]] = []

    def on_train_end(self, training_td: TensorDictBase, group: str) -> None:
        exp = self.experiment
        frames = exp.total_frames
        last = frames >= exp.config.max_n_frames
        if frames % SELECT_EVERY and not last:
            return
        start = time.perf_counter()
        ttd = float(np.mean([play(exp.test_env, exp.policy, s)["ttd"] for s in SELECTION_SEEDS]))
        self.log.append({"frames": frames, "ttd": ttd, "wall_s": time.perf_counter() - start})
        print(f"frames {frames}: selection TTD {ttd:.1f}", flush=True)
        if ttd < self.best:
            self.best = ttd
            torch.save({"policy": exp.policy.state_dict(), "frames": frames}, self.out / "best.pt")
        if last:
            torch.save({"policy": exp.policy.state_dict(), "frames": frames}, self.out / "final.pt")
        (self.out / "selection.json").write_text(json.dumps(self.log, indent=1))


def train(frames: int, out: Path) -> None:
    torch.set_num_threads(1)
    start = time.perf_counter()
    exp = experiment(frames, out, callbacks=(Selection(out),))
    exp.run()
    wall = time.perf_counter() - start
    frames = exp.total_frames
    print(f"trained {frames} frames in {wall:.0f} s ({frames / wall:.0f} frames/s)")
    (out / "train.json").write_text(json.dumps({"frames": exp.total_frames, "wall_s": wall}))


def rtaw_eval_policies(sim_keys: dict, cfg: dict) -> dict[str, dict[str, list[float]]]:
    """MPDM, lookahead and RTAW+ on the bare simulator, as ``rtaw-eval`` runs them."""
    sim = build_sim(SimSpec.of(sim_keys, cfg["layout"], cfg["navigator"], cfg["tasks"]))
    policies = {
        "mpdm": make_baseline("mpdm"),
        "lookahead": make_baseline("lookahead"),
        "rtaw+": load_policy(pretrained_path(RTAW_PLUS), name="rtaw+"),
    }
    return evaluate(sim, policies, EVAL_SEEDS)


def fmt(diff: PairedDiff) -> str:
    """``+3.1% [+1.2, +5.0]*`` as in docs/results.md."""
    star = "*" if diff.significant else ""
    return f"{diff.pct:+.1f}% [{diff.pct_low:+.1f}, {diff.pct_high:+.1f}]{star}"


def evaluate_run(out: Path, checkpoint: str) -> dict:
    torch.set_num_threads(1)
    exp = experiment(8192, out / "eval")
    saved = torch.load(out / checkpoint, weights_only=True)
    exp.policy.load_state_dict(saved["policy"])
    env = exp.test_env
    cfg = load_task_config()
    start = time.perf_counter()
    bench = [play(env, exp.policy, s) for s in EVAL_SEEDS]
    print(f"benchmarl: {time.perf_counter() - start:.0f} s", flush=True)
    mpdm_rule = MPDM(scale=env.base_env._env.unwrapped.scale)
    mpdm_path = []
    for s in EVAL_SEEDS:
        mpdm_rule.reset(s)
        mpdm_path.append(play(env, RulePolicy(env, mpdm_rule), s)["ttd"])
    sim_keys = {k: cfg[k] for k in ("num_robots", "num_tasks", "queue_len", "episode_mode")}
    sim_results = rtaw_eval_policies({**sim_keys, **cfg["sim"]}, cfg)
    same = mpdm_path == sim_results["mpdm"]["ttd"]
    print(f"MPDM through the wrapper == rtaw_marl.evaluation: {same}")
    if not same:
        raise SystemExit(f"MPDM differs: {mpdm_path} vs {sim_results['mpdm']['ttd']}")
    ttd = [row["ttd"] for row in bench]
    names = ("mpdm", "lookahead", "rtaw+")
    comparisons = {name: paired_difference(sim_results[name]["ttd"], ttd) for name in names}
    row = (
        f"| BenchMARL MAPPO (MLP), {saved['frames']:,} frames | {np.mean(ttd):.0f} | "
        + " | ".join(fmt(comparisons[n]) for n in names)
        + f" | {100 * np.mean([r['nearest_rate'] for r in bench]):.0f}% |"
    )
    print(row)
    for name in names:
        print(f"{name}: mean TTD {np.mean(sim_results[name]['ttd']):.0f}")
    payload = {
        "checkpoint": checkpoint,
        "frames": saved["frames"],
        "seeds": EVAL_SEEDS,
        "benchmarl": {key: [r[key] for r in bench] for key in bench[0]},
        "mpdm_through_wrapper": mpdm_path,
        "policies": sim_results,
        "comparisons": {name: diff.as_dict() for name, diff in comparisons.items()},
        "row": row,
    }
    write_json_atomic(ROOT / "benchmarks" / "data" / "benchmarl.json", payload)
    return payload


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("command", choices=("train", "evaluate"))
    parser.add_argument("--frames", type=int, default=409_600, help="training frames")
    parser.add_argument("--out", type=Path, default=ROOT / "runs" / "benchmarl")
    parser.add_argument("--checkpoint", default="best.pt", help="best.pt or final.pt")
    args = parser.parse_args()
    if args.command == "train":
        train(args.frames, args.out)
    else:
        evaluate_run(args.out, args.checkpoint)
    return 0


if __name__ == "__main__":
    sys.exit(main())
