"""A warm start by imitation: behaviour cloning of a rule, then DAgger, before PPO.

Round 0 follows the teacher (``lookahead``, ``hindsight`` or ``search``) on the batched simulators
and records the policy's observations with the teacher's choice; each later round lets
the *student* (the actor, greedy) drive, so the states are the student's own, still
labelled by the teacher (DAgger with beta = 0 after the first round). After every round
the actor is fitted by cross-entropy on everything labelled so far. The critic is fitted
meanwhile to discounted returns of the student's rounds, so that PPO starts with a
critic that knows the warm-started policy's values.

The teacher acts on the simulators themselves (``act_sim``): ``hindsight`` sees the real
future, which no online policy can; imitating it teaches the choices that pay off on
average given what the observation shows. ``search`` is expert iteration: each round's
teacher is the search (:mod:`rtaw_marl.policies.search`) over the network as it is at
the round's start, an online policy stronger than the network alone, so the network
learns what its own search would choose and the next round's search starts stronger.
"""

from __future__ import annotations

import copy
import json
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from rtaw_marl.errors import missing_extra

# Without the training extra: one error that names it (errors.missing_extra), no traceback
# of a bare ModuleNotFoundError.
try:
    import torch
    from tensordict import TensorDict
    from tqdm import tqdm
except ModuleNotFoundError as exc:
    raise missing_extra(exc, __name__, "train") from None

from rtaw_marl.envs.mixed import MixedBatchedEnv
from rtaw_marl.envs.torchrl import BatchedWarehouseEnv
from rtaw_marl.models.actor_critic import greedy_action
from rtaw_marl.models.checkpoint import Actor, Critic
from rtaw_marl.policies import BaselinePolicy, Hindsight, make_baseline
from rtaw_marl.policies.config import BaselinesConfig, SearchConfig
from rtaw_marl.policies.network import NetworkPolicy
from rtaw_marl.policies.search_policy import SearchPolicy, load_search
from rtaw_marl.sim.builder import SimSpec
from rtaw_marl.training.config import ImitationConfig
from rtaw_marl.utils.atomic import atomic_write

__all__ = ["IMITATION_FILE", "ImitationLog", "imitate"]


@dataclass
class _Round:
    """One round's labelled decisions ``[T, B]`` and the critic's targets (NaN where
    there is none: the teacher's round, and the stretch's cut-short end)."""

    observations: TensorDict
    labels: torch.Tensor
    returns: torch.Tensor


def imitate(
    cfg: ImitationConfig,
    spec: SimSpec,
    actor: Actor,
    critic: Critic,
    *,
    num_envs: int,
    seed: int,
    gamma: float,
    reward_scale: float,
    mix: Sequence[SimSpec] = (),
    progress: bool = False,
    after_round: Callable[[], dict[str, float]] | None = None,
) -> list[dict[str, float]]:
    """Warm-start ``actor`` (and ``critic``) in place; one row of figures per round.

    Args:
        cfg: The imitation settings (``cfg.teacher`` must be set).
        spec: The training simulator spec.
        actor: The policy network to fit.
        critic: The value network to fit to the student's returns.
        num_envs: Simulators stepped together.
        seed: Seed of the episodes (kept apart from PPO's and the evaluation's).
        gamma: PPO's discount, for the critic's targets.
        reward_scale: PPO's reward scale, for the critic's targets.
        mix: A mix's member specs (``num_envs / len(mix)`` simulators of each) instead
            of ``spec`` alone.
        progress: Show a progress bar of the labelled decisions (with its time left).
        after_round: Called after each round's fit; what it returns joins the round's
            row (the trainer's greedy evaluation on the selection seeds).

    Returns:
        Per round: ``round``, ``decisions`` labelled so far, ``agreement`` (how often the
        student already chose the teacher's task in the states it drove into), the
        fitted ``accuracy`` and ``loss``, and what ``after_round`` returned.
    """
    rule = None if cfg.teacher == "search" else make_baseline(cfg.teacher, params=BaselinesConfig())
    keys = tuple(dict.fromkeys((*actor.in_keys, *critic.in_keys)))
    if mix:
        share = num_envs // len(mix)
        env = MixedBatchedEnv([(member, share) for member in mix], seed=seed, keys=keys)
    else:
        env = BatchedWarehouseEnv(spec, num_envs, seed=seed, keys=keys)
    steps = max(1, cfg.frames // (cfg.rounds * num_envs))
    optim = torch.optim.Adam([*actor.parameters(), *critic.parameters()], lr=cfg.lr)
    rounds: list[_Round] = []
    rows = []
    total = cfg.rounds * steps * len(env.sims)
    bar = tqdm(total=total, desc="imitation", unit="dec", disable=not progress)
    for r in range(cfg.rounds):
        teacher = rule or _search_teacher(cfg.search, actor, critic, None if mix else reward_scale)
        teacher.reset(seed)  # its ties are broken by the run's seed, as everything else
        bar.set_postfix(round=r, teacher=cfg.teacher if r == 0 else "student")
        data, agreement = _collect(env, teacher, actor, keys, steps, student=r > 0, bar=bar)
        if r > 0:  # the critic learns the student's values, not the teacher's
            data.returns = _returns(data.observations, gamma, reward_scale)
        rounds.append(data)
        bar.set_postfix(round=r, fitting=sum(x.labels.numel() for x in rounds))
        fit = _fit(cfg, actor, critic, optim, rounds)
        row = {"round": r, "decisions": sum(x.labels.numel() for x in rounds),
               "agreement": agreement, **fit}  # fmt: skip
        if after_round is not None:
            row.update(after_round())
            if "ttd" in row:
                bar.set_postfix(
                    round=r, accuracy=f"{fit['accuracy']:.2f}", eval_ttd=f"{row['ttd']:.0f}"
                )
        rows.append(row)
    bar.close()
    return rows


def _search_teacher(
    cfg: SearchConfig, actor: Actor, critic: Critic, reward_scale: float | None
) -> SearchPolicy:
    """The search over ``cfg.policy``, or else over a frozen copy of the network being
    trained (this round's: expert iteration); ``reward_scale`` reads the critic's value
    in cells (``None``: a mix's rewards, in units of each member's ``L``)."""
    if cfg.policy is not None:
        return load_search(
            str(cfg.policy), width=cfg.width, horizon=cfg.horizon, leaf=cfg.leaf,
            torch_threads=None,
        )  # fmt: skip
    network = NetworkPolicy(copy.deepcopy(actor), name="search")
    return SearchPolicy(
        network, width=cfg.width, horizon=cfg.horizon, leaf=cfg.leaf,
        critic=copy.deepcopy(critic) if cfg.leaf > 0 else None, reward_scale=reward_scale,
    )  # fmt: skip


@torch.no_grad()
def _collect(
    env: BatchedWarehouseEnv,
    teacher: BaselinePolicy | Hindsight | SearchPolicy,
    actor: Actor,
    keys: tuple[str, ...],
    steps: int,
    *,
    student: bool,
    bar: tqdm,
) -> tuple[_Round, float]:
    """``steps`` decisions of every simulator, driven by the teacher or the student."""
    td = env.reset()
    frames, labels, agree = [], [], []
    for _ in range(steps):
        label = torch.tensor([teacher.act_sim(sim) for sim in env.sims])
        action = label
        if student:
            action = greedy_action(actor, td)
            agree.append((action == label).float().mean().item())
        td["action"] = action
        out = env.step(td)
        step = td.select(*keys, "action_mask", "action")
        frames.append(step.set("next", out["next"].select("reward", "done")))
        labels.append(label)
        bar.update(len(env.sims))
        td = out["next"]
        if bool(td["done"].any()):  # the finished simulators only (a mix's differ)
            # TorchRL keeps the other rows from the tensordict given: hand it all of them.
            td = env.reset(td.clone().set("_reset", td["done"].clone()))
    labels = torch.stack(labels)
    data = _Round(torch.stack(frames), labels, torch.full(labels.shape, torch.nan))
    return data, float(np.mean(agree)) if agree else float("nan")


def _returns(frames: TensorDict, gamma: float, reward_scale: float) -> torch.Tensor:
    """Discounted returns ``[T, B]`` within the collected stretch; NaN for the last
    ``1 / (1 - gamma)`` steps, whose returns the stretch cuts short."""
    reward = frames["next", "reward"].squeeze(-1) * reward_scale
    done = frames["next", "done"].squeeze(-1).to(reward.dtype)
    out = torch.zeros_like(reward)
    running = torch.zeros_like(reward[0])
    for t in range(reward.shape[0] - 1, -1, -1):
        running = reward[t] + gamma * (1.0 - done[t]) * running
        out[t] = running
    out[max(0, reward.shape[0] - round(1.0 / (1.0 - gamma))) :] = torch.nan
    return out


def _fit(
    cfg: ImitationConfig,
    actor: Actor,
    critic: Critic,
    optim: torch.optim.Optimizer,
    rounds: list[_Round],
) -> dict[str, float]:
    """Epochs of minibatches over every labelled decision so far."""
    obs = torch.cat([r.observations.reshape(-1) for r in rounds])
    labels = torch.cat([r.labels.reshape(-1) for r in rounds])
    returns = torch.cat([r.returns.reshape(-1) for r in rounds])
    has_return = ~returns.isnan()
    gen = torch.Generator().manual_seed(len(rounds))
    total = hits = 0
    loss_sum = 0.0
    for _ in range(cfg.epochs):
        for idx in torch.randperm(len(labels), generator=gen).split(cfg.minibatch_size):
            batch = obs[idx]
            mask = batch["action_mask"]
            logits = actor(*(batch[k] for k in actor.in_keys)).masked_fill(~mask, -1e9)
            loss = torch.nn.functional.cross_entropy(logits, labels[idx])
            valued = has_return[idx]
            if valued.any():
                value = critic(*(batch[k] for k in critic.in_keys)).squeeze(-1)
                loss = loss + torch.nn.functional.smooth_l1_loss(
                    value[valued], returns[idx][valued]
                )
            optim.zero_grad()
            loss.backward()
            optim.step()
            loss_sum += loss.item() * len(idx)
            hits += int((logits.argmax(-1) == labels[idx]).sum())
            total += len(idx)
    return {"accuracy": hits / max(total, 1), "loss": loss_sum / max(total, 1)}


#: The warm start's rows in the run folder, for the curve (a resumed run reads them).
IMITATION_FILE = "imitation.json"


class ImitationLog:
    """The warm start's rounds of a run (:func:`imitate`'s rows), kept in ``path``.

    Args:
        path: ``<run>/imitation.json``; what it holds is read now (none: no rows).
    """

    def __init__(self, path: Path) -> None:
        self.path = path
        self.rows: list[dict[str, float]] = []
        if path.exists():
            self.rows = [dict(row) for row in json.loads(path.read_text())]

    def save(self, rows: list[dict[str, float]]) -> None:
        """Keep ``rows`` (atomically)."""
        self.rows = [dict(row) for row in rows]
        data = json.dumps(self.rows, indent=1).encode()
        atomic_write(self.path, lambda fh: fh.write(data))
