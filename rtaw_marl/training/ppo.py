"""PPO training of the shared RTAW policy with TorchRL, readable top to bottom.

:func:`train` builds the learner (networks, ClipPPOLoss, GAE, Adam), the collector over
batched simulators and the evaluator, then loops: for each collected batch, GAE under
``no_grad``, ``epochs`` passes of shuffled minibatches, weight sync to the collector,
and every ``selection.every_frames`` a greedy evaluation on the selection seeds against
the rules, with checkpoints (last and best); at the end, the curve and the verdict:
``best.pt`` against the best rule on the evaluation seeds.
"""

from __future__ import annotations

import copy
import dataclasses
import json
import signal
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

from rtaw_marl.errors import ConfigError, missing_extra

# Without the training extra: one error that names it (errors.missing_extra), no traceback
# of a bare ModuleNotFoundError.
try:
    import torch
    from tensordict import TensorDictBase
    from torchrl.data import LazyTensorStorage, SamplerWithoutReplacement, TensorDictReplayBuffer
    from torchrl.objectives import ClipPPOLoss
    from torchrl.objectives.value import GAE
    from tqdm import tqdm
except ModuleNotFoundError as exc:
    raise missing_extra(exc, __name__, "train") from None

from rtaw_marl.models.actor_critic import make_actor, make_critic
from rtaw_marl.models.checkpoint import Actor, Critic, build_networks, load_networks
from rtaw_marl.scenarios.mix import mix_specs
from rtaw_marl.sim.builder import SimSpec
from rtaw_marl.training.checkpoints import (
    Checkpoints,
    Progress,
    clean_interrupted_writes,
    resume,
    score,
    trim_csv_logs,
)
from rtaw_marl.training.collectors import build_collector, learner_device
from rtaw_marl.training.config import PPOConfig, TrainConfig
from rtaw_marl.training.evaluator import Evaluator, greedy_ttd
from rtaw_marl.training.imitation import IMITATION_FILE, ImitationLog, imitate
from rtaw_marl.training.interop import (
    BATCHED_KEYS,
    INTEROP_KEYS,
    TrainKeys,
    acting_reward,
    standardize_acting_advantage,
)
from rtaw_marl.training.loggers import RunLogger, build_logger, check_installed, quiet_torchrl_logs
from rtaw_marl.training.progress import Clock, Estimate, WallClock
from rtaw_marl.training.verdict import Verdict, judge
from rtaw_marl.utils.atomic import atomic_write
from rtaw_marl.utils.plain import as_plain
from rtaw_marl.utils.runs import claim_folder
from rtaw_marl.utils.signals import Interrupted, deferred_interrupt
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
    #: The TTD of the selected (best) evaluation.
    best_ttd: float
    history: list[dict[str, float]] = field(default_factory=list)
    #: The selected (best) evaluation's row: what ``best.pt`` holds.
    best: dict[str, float] = field(default_factory=dict)
    #: The setting's strongest rule, the bar in each row (``<rule>_ttd``, ...).
    rule: str = "lookahead"
    #: Seconds spent per phase over the run (``time/collect_s``, ``time/update_s``, ...).
    timings: dict[str, float] = field(default_factory=dict)
    #: ``best.pt`` against the best rule on the evaluation seeds (``verdict=true``).
    verdict: Verdict | None = None


@dataclass
class Learner:
    """The networks and what updates them."""

    actor_net: Actor
    critic_net: Critic
    loss: ClipPPOLoss
    gae: GAE
    optim: torch.optim.Optimizer


def train(cfg: TrainConfig, run_dir: str | Path) -> TrainResult:
    """Train RTAW with PPO as configured; checkpoints and logs go to ``run_dir``.

    The run holds ``run_dir`` (no other run can write there meanwhile). Ctrl-C or
    SIGTERM saves ``last.pt`` and raises :class:`~rtaw_marl.utils.signals.Interrupted`
    (exit status ``128 + signal``) with a message saying how to resume.

    Raises:
        ConfigError: A config value is invalid, ``run_dir`` cannot be written, is in use,
            or already holds a run that is not being resumed.
    """
    _check(cfg)
    quiet_torchrl_logs()
    with claim_folder(run_dir) as run_dir:
        checkpoints = run_dir / "checkpoints"
        if (checkpoints / "last.pt").exists() and not cfg.resume:
            raise ConfigError(
                f"{run_dir} already holds a training run; pass "
                f"resume={checkpoints / 'last.pt'} to continue it, or choose another "
                "output_dir"
            )
        clean_interrupted_writes(checkpoints)
        return _train(cfg, run_dir)


def _train(cfg: TrainConfig, run_dir: Path) -> TrainResult:
    torch.manual_seed(cfg.seed)
    torch.set_num_threads(int(cfg.torch_threads))
    spec = cfg.sim_spec()
    keys = INTEROP_KEYS if cfg.interop else BATCHED_KEYS
    device = learner_device(cfg.device)
    learner = build_learner(cfg, keys, device)
    nets = (learner.actor_net, learner.critic_net)
    progress, history = Progress(), []
    if cfg.resume:
        progress, history = resume(cfg, nets, learner.optim, run_dir)
        trim_csv_logs(run_dir / "logs", progress.frames)
    wall = WallClock(history)
    evaluator = Evaluator(
        spec, [int(s) for s in cfg.selection.seeds], history, nets[0].in_keys, cfg.candidates,
        cfg.selection.metric, progress=cfg.progress,
    )  # fmt: skip
    # A mix's rewards come in units of each member's L already.
    reward_scale = cfg.algo.reward_scale or 1.0 / (1.0 if cfg.mix else evaluator.env.scale)
    logger = build_logger(run_dir, cfg.logger, config=as_plain(cfg))
    if cfg.init_actor is not None and progress.frames == 0:
        _init_actor(cfg, learner.actor_net)
    imitation = ImitationLog(run_dir / IMITATION_FILE)
    if cfg.imitation.teacher is not None and progress.frames == 0:
        _warm_start(cfg, spec, learner, logger, reward_scale, evaluator, wall, imitation)
    # Local worker processes or Ray actors; they act on CPUs, the learner on `device`.
    collector = build_collector(
        cfg, spec, learner.loss.actor_network, device, progress, observed(nets)
    )
    buffer = TensorDictReplayBuffer(
        storage=LazyTensorStorage(cfg.algo.frames_per_batch, device=device),
        sampler=SamplerWithoutReplacement(),
        batch_size=cfg.algo.minibatch_size,
    )
    saver = Checkpoints(cfg, run_dir / "checkpoints", nets, learner.optim, progress)
    bar = tqdm(
        total=cfg.frames, initial=progress.frames, desc="PPO", unit="fr", disable=not cfg.progress
    )  # fmt: skip
    start = time.perf_counter()

    postfix: dict[str, str] = {}
    eval_s: list[float] = []

    def evaluate_and_save() -> None:
        began = time.perf_counter()
        row = evaluator.run(_on_cpu(learner.actor_net), progress, wall())
        logger.log({f"eval/{k}": v for k, v in row.items() if k != "frames"}, progress.frames)
        postfix.update(_postfix(row, evaluator.rule, cfg.selection.metric))
        bar.set_postfix(postfix)
        saver.save(row, evaluator.history)
        eval_s.append(time.perf_counter() - began)

    next_eval = progress.frames + cfg.selection.every_frames
    frames_at_start = progress.frames
    totals: dict[str, float] = {}
    # Ctrl-C stops between iterations, never inside an update (see deferred_interrupt).
    with deferred_interrupt() as stop:
        try:
            # Not a step the history holds: a kill after the frame-0 evaluation leaves
            # a last.pt at 0 frames, and its resume must not evaluate frame 0 again.
            if progress.frames == 0 and not evaluator.history:
                evaluate_and_save()
            estimate = Estimate(cfg, progress.frames)
            clock = Clock()
            for data in collector:
                clock.lap("time/collect_s")
                progress.frames += data.numel()
                progress.iteration += 1
                stats = _train_step(cfg, learner, buffer, data, keys, reward_scale, progress, clock)
                collector.sync()
                clock.lap("time/sync_s")
                done = progress.frames >= cfg.frames
                if progress.frames >= next_eval or done:
                    next_eval += cfg.selection.every_frames
                    evaluate_and_save()
                clock.lap("time/eval_checkpoint_s")
                bar.update(data.numel())
                elapsed = time.perf_counter() - start
                stats["charts/fps"] = (progress.frames - frames_at_start) / elapsed
                logger.log({**stats, **clock.laps}, progress.frames)
                for name, seconds in clock.laps.items():
                    totals[name] = totals.get(name, 0.0) + seconds
                clock.reset()
                postfix["eta"] = estimate.report(progress.frames, totals, eval_s)
                bar.set_postfix(postfix)
                if done or stop.requested:
                    break
        except KeyboardInterrupt:  # a second Ctrl-C: stop now, still save
            stop.requested = True
        finally:
            collector.shutdown()
            bar.close()
            logger.close()
    if stop.requested:
        raise Interrupted(_interrupted(saver, evaluator.history), stop.signum or signal.SIGINT)
    return _finish(cfg, spec, run_dir, evaluator, saver, imitation, totals)


def _interrupted(saver: Checkpoints, history: list[dict[str, float]]) -> str:
    """Save ``last.pt`` on Ctrl-C; the one-line message for the user."""
    path = saver.save_last(history)
    if path is None:
        return "stopped before the first evaluation; no checkpoint was written"
    frames = saver.progress.frames
    return f"{path} saved at {frames} frames; continue with resume={path}"


def _postfix(row: dict[str, float], rule: str, metric: str) -> dict[str, str]:
    """The progress bar's figures: the policy's last evaluation, MPDM's and the best
    rule's, on the selection seeds."""
    key = "tasks_finished" if metric == "tasks_finished" else "ttd"
    short = "tasks" if metric == "tasks_finished" else "ttd"
    return {
        f"eval_{short}": f"{row[key]:.0f}",
        f"mpdm_{short}": f"{row[f'mpdm_{key}']:.0f}",
        "best_rule": f"{rule} {row[f'{rule}_{key}']:.0f}",
    }


def _finish(
    cfg: TrainConfig,
    spec: SimSpec,
    run_dir: Path,
    evaluator: Evaluator,
    saver: Checkpoints,
    imitation: ImitationLog,
    totals: dict[str, float],
) -> TrainResult:
    """The curve, the verdict on the evaluation seeds, the result."""
    plot_training_curve(
        evaluator.history, run_dir / "training_curve.png", rules=evaluator.rules,
        rule=evaluator.rule, metric=cfg.selection.metric, imitation=imitation.rows,
    )  # fmt: skip
    best = min(evaluator.history, key=lambda r: (score(r), r["frames"]))
    verdict = None
    if cfg.verdict:
        verdict = judge(
            spec, saver.best, evaluator.rule, evaluator.seeds, metric=cfg.selection.metric,
            candidates=cfg.candidates, progress=cfg.progress,
        )  # fmt: skip
        data = json.dumps(verdict.as_dict(), indent=2).encode()
        atomic_write(run_dir / "verdict.json", lambda fh: fh.write(data))
    return TrainResult(
        run_dir, saver.last, saver.best, saver.progress.frames, evaluator.mpdm_ttd,
        best["ttd"], evaluator.history, timings=totals, best=best, rule=evaluator.rule,
        verdict=verdict,
    )  # fmt: skip


def _warm_start(
    cfg: TrainConfig,
    spec: SimSpec,
    learner: Learner,
    logger: RunLogger,
    reward_scale: float,
    evaluator: Evaluator,
    wall: WallClock,
    log: ImitationLog,
) -> None:
    """Imitation rounds before PPO (their own episode seeds, on CPU), logged as
    ``imitation/*``; after each round the network plays the selection seeds greedily
    (the curve's imitation phase, kept in ``imitation.json``)."""
    actor, critic = _on_cpu(learner.actor_net), _on_cpu(learner.critic_net)

    def after_round() -> dict[str, float]:
        return {**evaluator.measure(actor), "wall_s": wall()}

    imitation = cfg.imitation
    if imitation.teacher == "best":  # the rule the run is judged against
        imitation = dataclasses.replace(imitation, teacher=evaluator.rule)
    rows = imitate(
        imitation, spec, actor, critic,
        num_envs=cfg.collector.envs_per_worker, seed=cfg.seed * 7919 + 104_729,
        gamma=cfg.algo.gamma, reward_scale=reward_scale, mix=mix_specs(cfg.mix),
        progress=cfg.progress, after_round=after_round,
    )  # fmt: skip
    log.save(rows)
    if actor is not learner.actor_net:  # a GPU learner: bring the warm start over
        learner.actor_net.load_state_dict(actor.state_dict())
        learner.critic_net.load_state_dict(critic.state_dict())
    # Before the first PPO frame: logged at frame 0, on their own axis (decisions).
    for row in rows:
        logger.log({f"imitation/{k}": v for k, v in row.items()}, 0, axis="imitation/decisions")


def _init_actor(cfg: TrainConfig, actor: torch.nn.Module) -> None:
    """Copy the actor weights of ``cfg.init_actor`` (a checkpoint or shipped name).

    Raises:
        ConfigError: The checkpoint is unreadable, or its actor is another network.
    """
    from rtaw_marl.models.checkpoint import load_checkpoint
    from rtaw_marl.policies.network import checkpoint_path

    path = checkpoint_path(cfg.init_actor)
    ckpt = load_checkpoint(path)
    # A checkpoint's model_config without a name is the paper's network.
    theirs = {"name": "rtaw", **ckpt["model_config"]}
    ours = dataclasses.asdict(cfg.model)
    keys = ("name", "embed_dim", "heads", "head_dim")
    differ = [k for k in keys if theirs.get(k, ours.get(k)) != ours.get(k)]
    if differ:
        k = differ[0]
        raise ConfigError(
            f"init_actor={cfg.init_actor}: its actor has model.{k}={theirs.get(k)!r}, this "
            f"run's model.{k}={ours.get(k)!r}"
        )
    actor.load_state_dict(load_networks(ckpt, path)[0].state_dict())
    print(f"actor initialised from {path}", file=sys.stderr, flush=True)


# --------------------------------------------------------------------------- building
def _check(cfg: TrainConfig) -> None:
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
    if cfg.interop and cfg.collector.backend != "local":
        raise ConfigError("interop=true runs in this process: set collector.backend=local")
    if cfg.interop and getattr(cfg.model, "fleet_summary", False):
        raise ConfigError(
            "interop=true trains on the AEC env's observation, which has no fleet summary: "
            "set model.fleet_summary=false"
        )
    check_installed(cfg.logger)  # before any simulator is built


def build_learner(cfg: TrainConfig, keys: TrainKeys, device: torch.device | None = None) -> Learner:
    """Actor and critic networks on ``device`` (CPU by default), the ClipPPO loss on
    explicit keys, GAE and Adam."""
    algo = cfg.algo
    device = device or torch.device("cpu")
    actor_net, critic_net = (net.to(device) for net in build_networks(cfg.model))
    actor = make_actor(actor_net, keys.observation(actor_net.in_keys))
    critic = make_critic(critic_net, keys.observation(critic_net.in_keys))
    loss = ClipPPOLoss(
        actor,
        critic,
        clip_epsilon=algo.clip_epsilon,
        entropy_coeff=algo.entropy_coeff_start,
        critic_coeff=algo.critic_coeff,
        loss_critic_type="smooth_l1",
        # The interop route standardises over the acting rows itself (_update).
        normalize_advantage=algo.normalize_advantage and keys.loss_mask is None,
    )
    shared_keys = {
        "value": keys.value,
        "reward": keys.reward,
        "done": keys.done,
        "terminated": keys.terminated,
        "advantage": keys.advantage,
        "value_target": keys.value_target,
    }
    loss.set_keys(action=keys.action, sample_log_prob=keys.log_prob, **shared_keys)
    # Interop route: only the acting robot's row of each step counts in the loss.
    loss.loss_mask_key = keys.loss_mask
    # shifted: one critic pass over [T + 1] steps instead of two over [T] (obs and next
    # obs); exact here, since next obs[t] is obs[t + 1] unless the episode ended at t.
    gae = GAE(
        gamma=algo.gamma, lmbda=algo.lmbda, value_network=critic, shifted=not cfg.interop,
        device=device,
    )  # fmt: skip
    gae.set_keys(**shared_keys)
    optim = torch.optim.Adam(loss.parameters(), lr=algo.lr)
    return Learner(actor_net, critic_net, loss, gae, optim)


def observed(nets: tuple[torch.nn.Module, ...]) -> tuple[str, ...]:
    """The observation entries the networks read, in order (the batched envs compute
    only these)."""
    return tuple(dict.fromkeys(key for net in nets for key in net.in_keys))


def _on_cpu(net: torch.nn.Module) -> torch.nn.Module:
    """``net`` itself on a CPU learner, else a CPU copy (evaluation, imitation)."""
    if next(net.parameters()).device.type == "cpu":
        return net
    return copy.deepcopy(net).cpu()


# --------------------------------------------------------------------------- update
def _train_step(
    cfg: TrainConfig,
    learner: Learner,
    buffer: TensorDictReplayBuffer,
    data: TensorDictBase,
    keys: TrainKeys,
    reward_scale: float,
    progress: Progress,
    clock: Clock,
) -> dict[str, float]:
    """Anneal the entropy coefficient, then one PPO update; returns the logged scalars."""
    algo = cfg.algo
    fraction = min(1.0, progress.frames / cfg.frames)
    entropy_coeff = algo.entropy_coeff_start + fraction * (
        algo.entropy_coeff_end - algo.entropy_coeff_start
    )
    learner.loss.entropy_coeff.fill_(entropy_coeff)
    raw_reward = acting_reward(data, keys)
    stats = _update(data, learner, buffer, algo, reward_scale, keys, clock)
    return {"train/reward_mean": raw_reward, "train/entropy_coeff": entropy_coeff, **stats}


#: ClipPPOLoss outputs averaged over an update's minibatches -> their logged names.
_LOSS_STATS = {
    "loss_objective": "losses/objective",
    "loss_critic": "losses/critic",
    "loss_entropy": "losses/entropy",
    "kl_approx": "losses/approx_kl",
    "clip_fraction": "losses/clip_fraction",
}


def _update(
    data: TensorDictBase,
    learner: Learner,
    buffer: TensorDictReplayBuffer,
    algo: PPOConfig,
    reward_scale: float,
    keys: TrainKeys,
    clock: Clock,
) -> dict[str, float]:
    """One PPO update on a collected batch ``[..., T]``: GAE, then epochs of minibatches."""
    data["next", keys.reward] = data["next", keys.reward] * reward_scale
    with torch.no_grad():
        learner.gae(data)
    if keys.loss_mask is not None and algo.normalize_advantage:
        standardize_acting_advantage(data, keys)
    buffer.extend(data.reshape(-1))
    clock.lap("time/gae_s")
    totals = dict.fromkeys(_LOSS_STATS.values(), 0.0)
    steps = 0
    for _ in range(algo.epochs):
        for batch in buffer:
            out = learner.loss(batch)
            loss = (
                algo.policy_coeff * out["loss_objective"] + out["loss_critic"] + out["loss_entropy"]
            )
            learner.optim.zero_grad()
            loss.backward()
            torch.nn.utils.clip_grad_norm_(learner.loss.parameters(), algo.max_grad_norm)
            learner.optim.step()
            for key, name in _LOSS_STATS.items():
                totals[name] += out[key].item()
            steps += 1
    clock.lap("time/update_s")
    return {k: v / max(steps, 1) for k, v in totals.items()}
