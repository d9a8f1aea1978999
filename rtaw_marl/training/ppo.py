"""PPO training of the shared RTAW policy with TorchRL, readable top to bottom.

build envs -> actor/critic -> ClipPPOLoss + GAE -> for each collected batch: GAE under
no_grad, ``epochs`` passes of shuffled minibatches, weight sync to the collector,
periodic greedy evaluation against MPDM on fixed seeds, checkpoints (last and best).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np
import torch
from omegaconf import DictConfig, OmegaConf
from tensordict import TensorDictBase
from torchrl.collectors import Collector, MultiSyncCollector
from torchrl.data import LazyTensorStorage, SamplerWithoutReplacement, TensorDictReplayBuffer
from torchrl.objectives import ClipPPOLoss
from torchrl.objectives.value import GAE
from tqdm import tqdm

from rtaw_marl.envs.torchrl import BatchedWarehouseEnv
from rtaw_marl.errors import ConfigError
from rtaw_marl.evaluation.evaluate import evaluate
from rtaw_marl.models.actor_critic import make_actor, make_critic
from rtaw_marl.models.checkpoint import build_networks, load_checkpoint, save_checkpoint
from rtaw_marl.models.rtaw import RTAWActor
from rtaw_marl.policies import MPDM
from rtaw_marl.sim.registry import build_sim
from rtaw_marl.training.interop import (
    BATCHED_KEYS,
    INTEROP_KEYS,
    TrainKeys,
    acting_reward,
    make_interop_env,
)
from rtaw_marl.training.logging import RunLogger
from rtaw_marl.viz.plots import plot_training_curve

__all__ = ["TrainResult", "greedy_ttd", "train"]


@dataclass
class TrainResult:
    """What a training run produced."""

    run_dir: Path
    last_checkpoint: Path
    best_checkpoint: Path
    frames: int
    mpdm_ttd: float
    best_ttd: float
    history: list[dict[str, float]] = field(default_factory=list)


def _env_spec(cfg: DictConfig) -> dict[str, Any]:
    return {
        "env": OmegaConf.to_container(cfg.env, resolve=True, throw_on_missing=True),
        "layout": OmegaConf.to_container(cfg.layout, resolve=True, throw_on_missing=True),
        "navigator": str(cfg.navigator.name),
        "tasks": OmegaConf.to_container(cfg.tasks, resolve=True, throw_on_missing=True),
    }


@torch.no_grad()
def greedy_ttd(net: RTAWActor, env: BatchedWarehouseEnv, seeds: list[int]) -> list[float]:
    """Total TTD of greedy (argmax) episodes, one per seed, run in lockstep.

    Args:
        net: The policy network.
        env: A batched env with ``len(seeds)`` simulators.
        seeds: Episode seeds.
    """
    td = env.reset_to(seeds)
    while True:
        mask = td["action_mask"]
        logits = net(td["robots"], td["tasks"], td["agent"], mask)
        td["action"] = logits.masked_fill(~mask, -torch.inf).argmax(-1)
        td = env.step(td)["next"]
        # Every simulator takes num_tasks decisions, so all finish on the same step.
        if bool(td["done"].all()):
            break
    return [env.sims[i].metrics().ttd for i in range(len(seeds))]


def _check(cfg: DictConfig) -> None:
    algo = cfg.algo
    if algo.frames_per_batch % algo.minibatch_size:
        raise ConfigError(
            f"algo.frames_per_batch={algo.frames_per_batch} must be a multiple of "
            f"algo.minibatch_size={algo.minibatch_size}"
        )
    per_collect = cfg.collector.workers * (1 if cfg.interop else cfg.collector.envs_per_worker)
    if algo.frames_per_batch % per_collect:
        raise ConfigError(
            f"algo.frames_per_batch={algo.frames_per_batch} must be a multiple of "
            f"collector.workers * collector.envs_per_worker = {per_collect}"
        )
    if cfg.interop and cfg.collector.workers != 1:
        raise ConfigError("interop=true runs one PettingZooWrapper env: set collector.workers=1")
    if cfg.frames < algo.frames_per_batch:
        raise ConfigError(f"frames={cfg.frames} is less than one batch ({algo.frames_per_batch})")


def train(cfg: DictConfig, run_dir: str | Path) -> TrainResult:
    """Train RTAW with PPO as configured; checkpoints and logs go to ``run_dir``."""
    _check(cfg)
    run_dir = Path(run_dir)
    ckpt_dir = run_dir / "checkpoints"
    if (ckpt_dir / "last.pt").exists() and not cfg.resume:
        raise ConfigError(
            f"{run_dir} already holds a training run; pass resume={ckpt_dir / 'last.pt'} "
            "to continue it, or choose another output_dir"
        )
    algo = cfg.algo
    torch.manual_seed(cfg.seed)
    torch.set_num_threads(int(cfg.torch_threads))
    spec = _env_spec(cfg)

    # --- networks, loss, optimiser ------------------------------------------------
    keys = INTEROP_KEYS if cfg.interop else BATCHED_KEYS
    model_cfg = OmegaConf.to_container(cfg.model, resolve=True)
    actor_net, critic_net = build_networks(model_cfg)
    actor, critic = (
        make_actor(actor_net, keys.observation),
        make_critic(critic_net, keys.observation),
    )
    loss_module = ClipPPOLoss(
        actor,
        critic,
        clip_epsilon=algo.clip_epsilon,
        entropy_coeff=algo.entropy_coeff_start,
        critic_coeff=algo.critic_coeff,
        loss_critic_type="smooth_l1",
        normalize_advantage=algo.normalize_advantage,
    )
    shared_keys = {
        "value": keys.value,
        "reward": keys.reward,
        "done": keys.done,
        "terminated": keys.terminated,
        "advantage": keys.advantage,
        "value_target": keys.value_target,
    }
    loss_module.set_keys(action=keys.action, sample_log_prob=keys.log_prob, **shared_keys)
    # Interop route: only the acting robot's row of each step counts in the loss.
    loss_module.loss_mask_key = keys.loss_mask
    gae = GAE(gamma=algo.gamma, lmbda=algo.lmbda, value_network=critic)
    gae.set_keys(**shared_keys)
    optim = torch.optim.Adam(loss_module.parameters(), lr=algo.lr)

    frames_done, iteration, best_ttd = 0, 0, float("inf")
    if cfg.resume:
        ckpt = load_checkpoint(cfg.resume)
        if ckpt["model_config"] != model_cfg:
            raise ConfigError(
                f"resume: checkpoint model {ckpt['model_config']} differs from model {model_cfg}"
            )
        actor_net.load_state_dict(ckpt["model"]["actor"])
        critic_net.load_state_dict(ckpt["model"]["critic"])
        optim.load_state_dict(ckpt["optimizer"])
        frames_done, iteration = int(ckpt["frames"]), int(ckpt["iteration"])
        best_ttd = float(ckpt.get("best_ttd", float("inf")))
        torch.manual_seed(cfg.seed + iteration)

    # --- evaluation reference: MPDM on the same seeds --------------------------------
    eval_seeds = [int(s) for s in cfg.eval.seeds]
    eval_env = BatchedWarehouseEnv(**spec, num_envs=len(eval_seeds), seed=0)
    mpdm_sim = build_sim(spec["env"], spec["layout"], spec["navigator"], spec["tasks"])
    mpdm_ttd = float(np.mean(evaluate(mpdm_sim, {"mpdm": MPDM()}, eval_seeds)["mpdm"]["ttd"]))

    # --- collector ------------------------------------------------------------------
    workers, envs = int(cfg.collector.workers), int(cfg.collector.envs_per_worker)
    # Env seeds depend on the resume point, so a resumed run sees new episodes.
    seeds = [int(cfg.seed) * 1009 + 31 * w + iteration for w in range(workers)]
    if cfg.interop:
        make_env = [partial(make_interop_env, spec, seed) for seed in seeds]
    else:
        make_env = [
            partial(BatchedWarehouseEnv, **spec, num_envs=envs, seed=seed) for seed in seeds
        ]
    batch = int(algo.frames_per_batch)
    remaining = max(int(cfg.frames) - frames_done, batch)
    collector_kwargs = {
        "frames_per_batch": batch,
        "total_frames": -(-remaining // batch) * batch,
        "auto_register_policy_transforms": False,
    }
    if workers == 1:
        collector = Collector(make_env[0], actor, **collector_kwargs)
    else:
        collector = MultiSyncCollector(make_env, actor, **collector_kwargs)
    collector.set_seed(int(cfg.seed) + iteration)

    buffer = TensorDictReplayBuffer(
        storage=LazyTensorStorage(int(algo.frames_per_batch)),
        sampler=SamplerWithoutReplacement(),
        batch_size=int(algo.minibatch_size),
    )
    logger = RunLogger(run_dir, cfg.logger)
    history: list[dict[str, float]] = []
    last_path, best_path = ckpt_dir / "last.pt", ckpt_dir / "best.pt"
    reward_scale = float(algo.reward_scale) if algo.reward_scale else 1.0 / eval_env.scale
    next_eval = frames_done + int(cfg.eval.every_frames)
    bar = tqdm(total=int(cfg.frames), initial=frames_done, unit="fr", disable=not cfg.progress)
    postfix: dict[str, str] = {}  # mean reward per decision, latest eval TTD, MPDM's TTD
    start = time.perf_counter()

    def checkpoint(eval_row: dict[str, float]) -> None:
        payload = {
            "model": {"actor": actor_net.state_dict(), "critic": critic_net.state_dict()},
            "model_config": model_cfg,
            "optimizer": optim.state_dict(),
            "config": OmegaConf.to_container(cfg, resolve=True),
            "frames": frames_done,
            "iteration": iteration,
            "best_ttd": best_ttd,
            "eval": eval_row,
        }
        save_checkpoint(last_path, payload)
        if eval_row.get("ttd", float("inf")) <= best_ttd:
            save_checkpoint(best_path, payload)

    def run_eval() -> dict[str, float]:
        nonlocal best_ttd
        ttd = float(np.mean(greedy_ttd(actor_net, eval_env, eval_seeds)))
        best_ttd = min(best_ttd, ttd)
        row = {
            "frames": frames_done,
            "ttd": ttd,
            "mpdm_ttd": mpdm_ttd,
            "improvement_pct": 100.0 * (mpdm_ttd - ttd) / mpdm_ttd,
            "wall_s": time.perf_counter() - start,
        }
        history.append(row)
        logger.log({f"eval/{k}": v for k, v in row.items() if k != "frames"}, frames_done)
        postfix.update(eval_ttd=f"{ttd:.0f}", mpdm_ttd=f"{mpdm_ttd:.0f}")
        bar.set_postfix(postfix)
        return row

    try:
        if frames_done == 0:
            checkpoint(run_eval())
        for data in collector:
            frames_done += data.numel()
            iteration += 1
            progress = min(1.0, frames_done / int(cfg.frames))
            entropy_coeff = algo.entropy_coeff_start + progress * (
                algo.entropy_coeff_end - algo.entropy_coeff_start
            )
            loss_module.entropy_coeff.fill_(entropy_coeff)
            raw_reward = acting_reward(data, keys)
            stats = _update(data, gae, loss_module, optim, buffer, algo, reward_scale, keys)
            collector.update_policy_weights_()
            postfix["reward"] = f"{raw_reward:.2f}"
            bar.set_postfix(postfix, refresh=False)
            bar.update(data.numel())
            logger.log(
                {
                    "train/reward_mean": raw_reward,
                    "train/entropy_coeff": entropy_coeff,
                    "charts/fps": frames_done / (time.perf_counter() - start),
                    **stats,
                },
                frames_done,
            )
            if frames_done >= next_eval or frames_done >= int(cfg.frames):
                next_eval += int(cfg.eval.every_frames)
                checkpoint(run_eval())
            if frames_done >= int(cfg.frames):
                break
    finally:
        collector.shutdown()
        bar.close()
        logger.close()
    plot_training_curve(history, run_dir / "training_curve.png")
    return TrainResult(run_dir, last_path, best_path, frames_done, mpdm_ttd, best_ttd, history)


def _update(
    data: TensorDictBase,
    gae: GAE,
    loss_module: ClipPPOLoss,
    optim: torch.optim.Optimizer,
    buffer: TensorDictReplayBuffer,
    algo: DictConfig,
    reward_scale: float,
    keys: TrainKeys,
) -> dict[str, float]:
    """One PPO update on a collected batch ``[..., T]``: GAE, then epochs of minibatches."""
    data["next", keys.reward] = data["next", keys.reward] * reward_scale
    with torch.no_grad():
        gae(data)
    buffer.extend(data.reshape(-1))
    totals = {"losses/objective": 0.0, "losses/critic": 0.0, "losses/entropy": 0.0}
    steps = 0
    for _ in range(int(algo.epochs)):
        for batch in buffer:
            out = loss_module(batch)
            loss = (
                algo.policy_coeff * out["loss_objective"] + out["loss_critic"] + out["loss_entropy"]
            )
            optim.zero_grad()
            loss.backward()
            torch.nn.utils.clip_grad_norm_(loss_module.parameters(), algo.max_grad_norm)
            optim.step()
            totals["losses/objective"] += out["loss_objective"].item()
            totals["losses/critic"] += out["loss_critic"].item()
            totals["losses/entropy"] += out["loss_entropy"].item()
            steps += 1
    return {k: v / max(steps, 1) for k, v in totals.items()}
