"""Your policy against the rules, in one call, with paired 95% intervals.

    from rtaw_marl.evaluation import compare

    def nearest(sim):                      # a decision function: the slot for sim.robot
        distances = np.where(sim.queue_mask, sim.robot_distances(), np.inf)
        return int(distances.argmin())     # the nearest queued pickup

    result = compare(nearest, "C_astar_m10")          # seeds 0-19, against five rules
    print(result.table())                              # markdown, with intervals
    result.diffs["lookahead"].pct                      # % less TTD than lookahead
    result.to_csv("episodes.csv")                      # one row per policy and seed

Every policy plays the same seeds (the same tasks and noise), so each comparison is a
paired difference of total travel delay with a Student t interval
(:func:`~rtaw_marl.evaluation.stats.paired_difference`): positive percentages mean
your policy's TTD is lower. ``best`` names the bar to beat in this setting (it depends on
the setting): the rule of least mean TTD on the selection seeds 1000-1019
(:func:`~rtaw_marl.evaluation.best_rule.choose_best_rule`), never on the seeds reported.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from rtaw_marl.errors import ConfigError
from rtaw_marl.evaluation.best_rule import (
    DEFAULT_RULES,
    SELECTION_SEEDS,
    BestRule,
    choose_best_rule,
)
from rtaw_marl.evaluation.evaluate import SimPolicy, evaluate
from rtaw_marl.evaluation.report import format_table
from rtaw_marl.evaluation.stats import PairedDiff, paired_difference
from rtaw_marl.evaluation.tidy import episode_rows, write_episodes_csv
from rtaw_marl.policies import BaselinesConfig, make_baseline
from rtaw_marl.policies.user import as_policy
from rtaw_marl.scenarios import EVAL_SEEDS, Scenario, scenario
from rtaw_marl.sim.builder import SimSpec, build_sim
from rtaw_marl.sim.core import WarehouseSim
from rtaw_marl.sim.inputs import seed_list

__all__ = ["DEFAULT_RULES", "Comparison", "compare"]


@dataclass(frozen=True)
class Comparison:
    """What :func:`compare` measured.

    Attributes:
        label: The compared policy's label.
        seeds: The episode seeds, in the order of every per-seed list.
        results: ``{label: {metric: [one value per seed]}}``, the policy first, then
            the rules (every metric of :func:`~rtaw_marl.evaluation.evaluate`).
        diffs: Rule -> the paired TTD difference ``rule - policy`` (positive: the
            policy is better), with its interval, also in percent of the rule's mean.
        best: The bar: the rule of least mean TTD on the selection seeds (``best_rule``).
        confidence: The intervals' confidence level.
        best_rule: How ``best`` was chosen (every rule's mean on the selection seeds).
    """

    label: str
    seeds: list[int]
    results: dict[str, dict[str, list[float]]]
    diffs: dict[str, PairedDiff]
    best: str
    confidence: float = 0.95
    best_rule: BestRule | None = None

    def table(self) -> str:
        """A markdown table (TTD, makespan, waits, seconds per episode with intervals)
        and the paired differences against MPDM (when compared) and the best rule."""
        reference = "mpdm" if "mpdm" in self.results else self.best
        return format_table(
            self.results, reference, compare_to=self.best, confidence=self.confidence
        )

    def rows(self) -> list[dict[str, str | int | float]]:
        """One dict per (policy, seed) with every metric: ``pandas.DataFrame(rows())``."""
        return episode_rows(self.results, self.seeds)

    def to_csv(self, path: str | Path) -> Path:
        """Write :meth:`rows` as CSV (atomically); returns the path."""
        return write_episodes_csv(path, self.results, self.seeds)

    def __str__(self) -> str:
        return self.table()


def compare(
    policy: SimPolicy | Callable[[WarehouseSim], int],
    setting: str | Scenario | SimSpec,
    seeds: Sequence[int] = EVAL_SEEDS,
    against: Sequence[str] = DEFAULT_RULES,
    *,
    label: str | None = None,
    params: BaselinesConfig | None = None,
    confidence: float = 0.95,
    selection_seeds: Sequence[int] = SELECTION_SEEDS,
) -> Comparison:
    """Play ``policy`` and the rules ``against`` on the same seeds of ``setting``.

    Args:
        policy: A policy (``act_sim(sim)`` and ``reset(seed)``: every policy of
            :mod:`rtaw_marl.policies`, ``load_policy(...)``), a class that builds one
            without arguments, or a function ``choose(sim) -> slot``.
        setting: A named scenario (``"C_astar_m10"``, ``rtaw_marl.scenarios.SCENARIOS``),
            a :class:`~rtaw_marl.scenarios.Scenario`, or a
            :class:`~rtaw_marl.sim.builder.SimSpec` (your own map, fleet, task stream).
        seeds: Episode seeds, distinct; by default the evaluation seeds 0-19 (never
            train or select on them).
        against: Rules of :data:`~rtaw_marl.policies.BASELINES`, at least one.
        label: The policy's label; by default its ``name`` or function name.
        params: The rules' parameters (lookahead's horizon, ...); defaults when None.
        confidence: The intervals' confidence level.
        selection_seeds: The seeds ``best`` is chosen on (the rules ``against`` are
            played there first), disjoint from ``seeds``.

    Returns:
        The :class:`Comparison`.

    Raises:
        ConfigError: An unknown scenario or rule (the message lists the valid ones), no
            rule, a bad seed, selection seeds that are evaluation seeds or ``seeds``, a
            label equal to a rule's, or a policy that is none of the accepted kinds; all
            before any episode runs.
    """
    seeds = seed_list(seeds)
    rules = list(dict.fromkeys(against))
    if not rules:
        raise ConfigError("against must name at least one rule")
    shared = sorted(set(seed_list(selection_seeds)) & set(seeds))
    if shared:
        raise ConfigError(
            f"seed {shared[0]} is both a selection seed (where the best rule is chosen) "
            "and a reported seed; give seeds and selection_seeds that do not overlap"
        )
    played = as_policy(policy, name=label)
    name = label or getattr(played, "name", None) or type(played).__name__
    if name in rules:
        raise ConfigError(f"the policy's label {name!r} is also a rule's; give label=...")
    sim = build_sim(_spec(setting))
    policies = {name: played}
    for rule in rules:
        policies[rule] = make_baseline(rule, params=params)
    chosen = choose_best_rule(sim, rules, selection_seeds, params)
    results = evaluate(sim, policies, seeds)
    diffs = {
        rule: paired_difference(results[rule]["ttd"], results[name]["ttd"], confidence)
        for rule in rules
    }
    return Comparison(name, seeds, results, diffs, chosen.name, confidence, chosen)


def _spec(setting: Any) -> SimSpec:
    """The simulator spec of a scenario name, a scenario or a spec."""
    if isinstance(setting, SimSpec):
        return setting
    if isinstance(setting, Scenario):
        return setting.spec()
    if isinstance(setting, str):
        return scenario(setting).spec()
    raise ConfigError(
        f"setting must be a scenario name, a Scenario or a SimSpec, got {type(setting).__name__}"
    )
