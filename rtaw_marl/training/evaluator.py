"""Greedy evaluation during training: the policy against MPDM and the setting's strongest
rule on the selection seeds (never the evaluation seeds 0-19), all episodes in lockstep.

The strongest rule is ``lookahead`` (bounded by the run's ``candidates``), and
``pair_greedy`` under LoRR's reassignment (``sim.reassign``), where it finishes the most
tasks (docs/results.md, "Calibration")."""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np

from rtaw_marl.errors import missing_extra

# Without the training extra: one error that names it (errors.missing_extra), no traceback
# of a bare ModuleNotFoundError.
try:
    import torch
except ModuleNotFoundError as exc:
    raise missing_extra(exc, __name__, "train") from None

from rtaw_marl.decision.features import FEATURES
from rtaw_marl.envs.torchrl import BatchedWarehouseEnv
from rtaw_marl.evaluation.evaluate import evaluate
from rtaw_marl.models.actor_critic import greedy_action
from rtaw_marl.models.checkpoint import Actor
from rtaw_marl.policies import MPDM, make_baseline
from rtaw_marl.policies.config import BaselinesConfig
from rtaw_marl.sim.builder import SimSpec, build_sim
from rtaw_marl.training.checkpoints import Progress

__all__ = ["Evaluator", "bar_rule", "greedy_ttd"]


def bar_rule(spec: SimSpec) -> str:
    """The rule every curve shows as the bar to clear: ``pair_greedy`` under LoRR's
    reassignment, else ``lookahead``."""
    return "pair_greedy" if spec.sim.reassign else "lookahead"


class Evaluator:
    """Greedy evaluation on fixed selection seeds, in lockstep, against MPDM.

    Args:
        spec: The simulator spec.
        seeds: Selection seeds (never the evaluation seeds 0-19).
        history: Evaluations of the run so far (on resume).
        keys: The observation entries the evaluated network reads (its ``in_keys``).
        candidates: Decisions hold their ``K`` nearest tasks, as in training.
        metric: ``selection.metric``: each row's ``score`` (lower is better) is its mean
            TTD, or minus its mean tasks finished.
    """

    def __init__(
        self,
        spec: SimSpec,
        seeds: list[int],
        history: list[dict[str, float]] | None = None,
        keys: Iterable[str] = FEATURES,
        candidates: int | None = None,
        metric: str = "ttd",
    ) -> None:
        self.seeds, self.metric = seeds, metric
        self.env = BatchedWarehouseEnv(spec, len(seeds), seed=0, keys=keys, candidates=candidates)
        # The strongest rule of the setting, so that every curve shows the bar to clear.
        self.rule = bar_rule(spec)
        params = BaselinesConfig(lookahead_candidates=candidates)
        rules = {"mpdm": MPDM(), self.rule: make_baseline(self.rule, params=params)}
        results = evaluate(build_sim(spec), rules, seeds)
        ttd = {name: r["ttd"] for name, r in results.items()}
        self.mpdm_ttd = float(np.mean(ttd["mpdm"]))
        self.mpdm_tasks = float(np.mean(results["mpdm"]["tasks_finished"]))
        self.rule_ttd = float(np.mean(ttd[self.rule]))
        self.rule_tasks = float(np.mean(results[self.rule]["tasks_finished"]))
        self.history: list[dict[str, float]] = list(history or [])

    def run(self, net: Actor, progress: Progress, wall_s: float) -> dict[str, float]:
        """Evaluate ``net`` and return the logged row (``progress.best_score`` is left to
        :class:`~rtaw_marl.training.checkpoints.Checkpoints`, which keeps the best)."""
        ttd = float(np.mean(greedy_ttd(net, self.env, self.seeds)))
        row = {
            "frames": progress.frames,
            "ttd": ttd,
            "mpdm_ttd": self.mpdm_ttd,
            f"{self.rule}_ttd": self.rule_ttd,
            "improvement_pct": 100.0 * (self.mpdm_ttd - ttd) / self.mpdm_ttd,
            "score": ttd,
            "wall_s": wall_s,
        }
        if self.metric == "tasks_finished":
            # The episodes greedy_ttd just played, still in the env's simulators.
            tasks = float(np.mean([sim.metrics().tasks_finished for sim in self.env.sims]))
            row.update(tasks_finished=tasks, mpdm_tasks_finished=self.mpdm_tasks, score=-tasks)
            row[f"{self.rule}_tasks_finished"] = self.rule_tasks
        self.history.append(row)
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
