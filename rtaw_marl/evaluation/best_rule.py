"""The bar a policy must clear: the best rule of its setting, chosen on selection seeds.

Which hand-written rule is strongest depends on the setting: ``lookahead`` (a rollout
search) on one map, ``hungarian`` (the whole fleet's assignment) on another, ``batch``
with traffic. So a policy is compared with the best of :data:`DEFAULT_RULES` *there*.
Choosing that rule on the seeds the comparison is reported on would select on them (the
least of five means on the same seeds is luckily low); it is chosen on the selection
seeds (:data:`SELECTION_SEEDS`, 1000-1019, never an evaluation seed) and compared on
the evaluation seeds. Fixed-horizon episodes (LoRR's) are judged by tasks finished, the
others by total travel delay.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from rtaw_marl.errors import ConfigError
from rtaw_marl.evaluation.evaluate import evaluate
from rtaw_marl.policies import BaselinesConfig, make_baseline
from rtaw_marl.scenarios import EVAL_SEEDS
from rtaw_marl.sim.core import WarehouseSim
from rtaw_marl.sim.inputs import seed_list, seed_span

__all__ = ["BEST", "DEFAULT_RULES", "SELECTION_SEEDS", "BestRule", "choose_best_rule"]

#: ``compare_to=best``: the best rule of the setting.
BEST = "best"

#: The rules a policy is compared with unless told otherwise: the paper's MPDM and RBTS
#: and the stronger hand-written rules (a rollout search, a whole-fleet assignment, a
#: matching of the robots freed together). Which one is best depends on the setting.
DEFAULT_RULES: tuple[str, ...] = ("mpdm", "rbts", "lookahead", "hungarian", "batch")

#: The seeds the best rule is chosen on: 20 selection seeds, disjoint from the
#: evaluation seeds 0-19 (as the training runs' checkpoint selection).
SELECTION_SEEDS: tuple[int, ...] = tuple(range(1000, 1020))


@dataclass(frozen=True)
class BestRule:
    """The rule chosen as the bar, and what it was chosen on.

    Attributes:
        name: The chosen rule.
        metric: ``"ttd"`` (least mean wins) or ``"tasks_finished"`` (most wins, in
            fixed-horizon episodes).
        scores: Rule -> its mean ``metric`` on the selection seeds.
        seeds: The selection seeds.
    """

    name: str
    metric: str
    scores: dict[str, float]
    seeds: tuple[int, ...]

    def line(self) -> str:
        """One line for a report: the choice and every rule's score."""
        scores = ", ".join(f"{rule} {score:,.1f}" for rule, score in self.scores.items())
        span = seed_span(self.seeds)
        return f"best rule on selection seeds {span}: {self.name} (mean {self.metric}: {scores})"

    def as_dict(self) -> dict[str, Any]:
        """Plain values, for results files."""
        return {
            "name": self.name, "metric": self.metric, "scores": dict(self.scores),
            "seeds": list(self.seeds),
        }  # fmt: skip


def choose_best_rule(
    sim: WarehouseSim,
    rules: Sequence[str] = DEFAULT_RULES,
    seeds: Sequence[int] = SELECTION_SEEDS,
    params: BaselinesConfig | None = None,
) -> BestRule:
    """Play ``rules`` on ``seeds`` of ``sim``'s setting and return the best.

    Args:
        sim: The setting's simulator (episodes are reset on each seed).
        rules: Rules of :data:`~rtaw_marl.policies.BASELINES`, at least one.
        seeds: Selection seeds; none may be an evaluation seed (0-19).
        params: The rules' parameters; defaults when None.

    Returns:
        The :class:`BestRule` (ties: the first of ``rules``).

    Raises:
        ConfigError: No rule, an unknown rule, or a seed that is an evaluation seed.
    """
    rules = list(dict.fromkeys(rules))
    if not rules:
        raise ConfigError("the best rule is chosen among at least one rule")
    seeds = seed_list(seeds)
    overlap = sorted(set(seeds) & set(EVAL_SEEDS))
    if overlap:
        raise ConfigError(
            f"the best rule is chosen on selection seeds, never on evaluation seeds "
            f"(0-19); got {overlap[0]}"
        )
    policies = {rule: make_baseline(rule, params=params) for rule in rules}
    results = evaluate(sim, policies, seeds)
    horizon = sim.config.episode_mode == "horizon"
    metric = "tasks_finished" if horizon else "ttd"
    scores = {rule: float(np.mean(results[rule][metric])) for rule in rules}
    pick = max if horizon else min
    name = pick(rules, key=lambda rule: scores[rule])
    return BestRule(name, metric, scores, tuple(seeds))
