"""Greedy evaluation during training: the policy against the rules on the selection seeds
(never the evaluation seeds 0-19), all episodes in lockstep.

The rules are those a policy is judged against
(:data:`~rtaw_marl.evaluation.best_rule.DEFAULT_RULES`: MPDM, RBTS, ``lookahead``,
``hungarian``, ``batch``; ``lookahead`` bounded by the run's ``candidates``), or MPDM and
``pair_greedy`` under LoRR's reassignment (``sim.reassign``), where ``pair_greedy``
finishes the most tasks (docs/results.md, "Calibration") and is the bar. Otherwise the
best of them on the selection seeds is the run's bar: on its progress bar, in its curve
and in its verdict (:mod:`rtaw_marl.training.verdict`)."""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np

from rtaw_marl.errors import missing_extra

# Without the training extra: one error that names it (errors.missing_extra), no traceback
# of a bare ModuleNotFoundError.
try:
    import torch
    from tqdm import tqdm
except ModuleNotFoundError as exc:
    raise missing_extra(exc, __name__, "train") from None

from rtaw_marl.decision.features import FEATURES
from rtaw_marl.envs.torchrl import BatchedWarehouseEnv
from rtaw_marl.evaluation.best_rule import DEFAULT_RULES
from rtaw_marl.evaluation.evaluate import evaluate
from rtaw_marl.models.actor_critic import greedy_action
from rtaw_marl.models.checkpoint import Actor
from rtaw_marl.policies import make_baseline
from rtaw_marl.policies.config import BaselinesConfig
from rtaw_marl.sim.builder import SimSpec, build_sim
from rtaw_marl.training.checkpoints import Progress

__all__ = ["Evaluator", "greedy_ttd", "training_rules"]


def training_rules(spec: SimSpec) -> tuple[str, ...]:
    """The rules a run is measured against: MPDM and ``pair_greedy`` under LoRR's
    reassignment, else :data:`~rtaw_marl.evaluation.best_rule.DEFAULT_RULES`."""
    return ("mpdm", "pair_greedy") if spec.sim.reassign else DEFAULT_RULES


class Evaluator:
    """Greedy evaluation on fixed selection seeds, in lockstep, against the rules.

    Attributes:
        rules: Rule -> its value of the selection metric per seed (``ttd``, or
            ``tasks_finished`` with ``metric="tasks_finished"``), played once.
        rule: The best of them by mean (least TTD, most tasks): the bar to clear;
            ``pair_greedy`` under reassignment.

    Args:
        spec: The simulator spec.
        seeds: Selection seeds (never the evaluation seeds 0-19).
        history: Evaluations of the run so far (on resume).
        keys: The observation entries the evaluated network reads (its ``in_keys``).
        candidates: Decisions hold their ``K`` nearest tasks, as in training.
        metric: ``selection.metric``: each row's ``score`` (lower is better) is its mean
            TTD, or minus its mean tasks finished.
        progress: Show a progress bar while the rules play (the run's first phase).
    """

    def __init__(
        self,
        spec: SimSpec,
        seeds: list[int],
        history: list[dict[str, float]] | None = None,
        keys: Iterable[str] = FEATURES,
        candidates: int | None = None,
        metric: str = "ttd",
        progress: bool = False,
    ) -> None:
        self.seeds, self.metric = seeds, metric
        self.env = BatchedWarehouseEnv(spec, len(seeds), seed=0, keys=keys, candidates=candidates)
        params = BaselinesConfig(lookahead_candidates=candidates)
        sim = build_sim(spec)
        self.rules: dict[str, list[float]] = {}
        self._means: dict[str, float] = {}  # row entries: <rule>_ttd, <rule>_tasks_finished
        for name in tqdm(training_rules(spec), desc="rules", unit="rule", disable=not progress):
            result = evaluate(sim, {name: make_baseline(name, params=params)}, seeds)[name]
            self.rules[name] = [float(v) for v in result[metric]]
            self._means[f"{name}_ttd"] = float(np.mean(result["ttd"]))
            if metric == "tasks_finished":
                self._means[f"{name}_tasks_finished"] = float(np.mean(result[metric]))
        # The strongest rule of the setting, so that every curve shows the bar to clear;
        # under reassignment the winner's rule, MPDM beside it as the paper's baseline.
        bar = ("pair_greedy",) if spec.sim.reassign else tuple(self.rules)
        best = max if metric == "tasks_finished" else min
        self.rule = best(bar, key=lambda name: float(np.mean(self.rules[name])))
        self.mpdm_ttd = self._means["mpdm_ttd"]
        self.history: list[dict[str, float]] = list(history or [])

    def run(self, net: Actor, progress: Progress, wall_s: float) -> dict[str, float]:
        """Evaluate ``net`` and return the logged row (``progress.best_score`` is left to
        :class:`~rtaw_marl.training.checkpoints.Checkpoints`, which keeps the best)."""
        row = {"frames": progress.frames, **self.measure(net), "wall_s": wall_s}
        self.history.append(row)
        return row

    def measure(self, net: Actor) -> dict[str, float]:
        """``net``'s greedy episodes on the selection seeds beside the rules' means:
        ``ttd``, ``score`` (lower is better), ``improvement_pct`` over MPDM, every
        ``<rule>_ttd`` (and ``tasks_finished``, ``<rule>_tasks_finished`` when selecting
        on tasks finished)."""
        ttd = float(np.mean(greedy_ttd(net, self.env, self.seeds)))
        row = {
            "ttd": ttd,
            **self._means,
            "improvement_pct": 100.0 * (self.mpdm_ttd - ttd) / self.mpdm_ttd,
            "score": ttd,
        }
        if self.metric == "tasks_finished":
            # The episodes greedy_ttd just played, still in the env's simulators.
            tasks = float(np.mean([sim.metrics().tasks_finished for sim in self.env.sims]))
            row.update(tasks_finished=tasks, score=-tasks)
        return row


@torch.no_grad()
def greedy_ttd(net: Actor, env: BatchedWarehouseEnv, seeds: list[int]) -> list[float]:
    """Total TTD of greedy (argmax) episodes, one per seed, run in lockstep.

    Args:
        net: The policy network.
        env: A batched env with ``len(seeds)`` simulators.
        seeds: Episode seeds.
    """
    td = env.reset_to(seeds)
    while True:
        td["action"] = greedy_action(net, td)
        td = env.step(td)["next"]
        # Ended simulators ignore their actions until all have ended (horizon episodes
        # end after different numbers of decisions).
        if bool(td["done"].all()):
            break
    return [env.sims[i].metrics().ttd for i in range(len(seeds))]
