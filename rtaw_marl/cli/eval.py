"""``rtaw-eval``: evaluate policies on seeded episodes and write ``results.json``.

Examples::

    rtaw-eval scenario=poc policy=[mpdm,rbts]
    rtaw-eval sim.num_robots=100 sim.num_tasks=500 navigator=astar layout=open seeds=[0,1,2]
    rtaw-eval --multirun sim.num_robots=10,100 navigator=direct,astar
    rtaw-eval policy=[mpdm,rbts,checkpoint] checkpoint=[runs/a/best.pt,runs/b/best.pt]
    rtaw-eval policy=[mpdm,rbts,hindsight] compare_to=rbts lower_bound=true
    rtaw-eval policy=[mpdm,pretrained] pretrained=generalist_plus compare_to=best
    rtaw-eval ... output=runs/big/results.json resume=true   # after a kill: skip finished episodes

Episodes run seed by seed (every policy on a seed, then the next seed), so that a run
estimated to take over a minute prints ``estimated time: ...`` from its first seeds;
the progress bar counts the decisions still to run and shows the time left. Ctrl-C or
SIGTERM stops with one line saying how many finished episodes the journal keeps (exit
130 or 143); the same command with ``resume=true`` continues. The journal matches
episodes by the contents of the files they depend on (map, task file, checkpoints).

The report (the layout line, the tables, notes) goes to stdout and is saved as
``<stem>.txt`` beside ``results.json`` (``results.txt``), and one row per policy and
seed with every metric as a column in ``<stem>.csv`` (``pandas.read_csv`` loads it as
is); progress goes to stderr: the
bar only when stderr is a terminal, the ``estimated time`` line always. So
``rtaw-eval ... > table.txt`` is a clean table file. ``s/episode`` is each policy's
mean wall time per episode after an untimed warm-up of a few decisions
(:data:`~rtaw_marl.evaluation.evaluate.WARM_UP_DECISIONS`), so one-time compilation
is charged to no policy.

``compare_to=best`` compares every policy with the best rule of the setting, chosen
first on the selection seeds 1000-1019 (:mod:`rtaw_marl.evaluation.best_rule`: the
strongest rule depends on the setting, and choosing it on the reported seeds would be
selecting on them); the report's first line names it and every rule's score there.
"""

from __future__ import annotations

import signal
import sys
import time
from collections.abc import Mapping
from pathlib import Path

from hydra.core.hydra_config import HydraConfig
from omegaconf import DictConfig
from tqdm import tqdm

from rtaw_marl.cli.common import (
    as_list,
    hydra_entry,
    learned_files,
    policies_from_cfg,
    policy_names,
    typed,
)
from rtaw_marl.config import as_plain
from rtaw_marl.errors import ConfigError
from rtaw_marl.evaluation import evaluate, format_table, write_json_atomic
from rtaw_marl.evaluation.best_rule import (
    BEST,
    DEFAULT_RULES,
    SELECTION_SEEDS,
    BestRule,
    choose_best_rule,
)
from rtaw_marl.evaluation.config import EvalConfig
from rtaw_marl.evaluation.evaluate import SimPolicy, TimeEstimate
from rtaw_marl.evaluation.journal import (
    NOT_SETTING,
    EpisodeJournal,
    file_digest,
    journal_path,
    with_file_digests,
)
from rtaw_marl.evaluation.lower_bound import ttd_lower_bound
from rtaw_marl.evaluation.report import gap_to_bound
from rtaw_marl.evaluation.results_file import results_payload
from rtaw_marl.evaluation.throughput import throughput_table
from rtaw_marl.evaluation.tidy import write_episodes_csv
from rtaw_marl.evaluation.transcript import Transcript, progress_shown, transcript_path
from rtaw_marl.policies.spec import PolicySpec
from rtaw_marl.sim.builder import build_sim
from rtaw_marl.sim.core import WarehouseSim
from rtaw_marl.utils.runs import claim_file
from rtaw_marl.utils.signals import Interrupted

#: The main baseline every policy is compared with (when it is evaluated).
REFERENCE = "mpdm"


def run(cfg: DictConfig | EvalConfig) -> dict:
    """Evaluate ``cfg.policy`` on ``cfg.seeds`` and write the results; returns them."""
    cfg = typed(cfg)
    names = as_list(cfg.policy)
    if not names:
        raise ConfigError("policy must name at least one policy")
    seeds = cfg.seeds  # distinct integers >= 0: EvalConfig checked them
    output = Path(cfg.output or f"{HydraConfig.get().runtime.output_dir}/results.json")
    # Checked and held before any work, so a bad path does not cost a whole evaluation
    # and two runs never write the same results.
    siblings = (journal_path(output).name, transcript_path(output).name, _csv(output).name)
    if output.name in siblings:
        raise ConfigError(
            f"output={output}: the per-episode table {_csv(output).name} and the "
            "report are written beside it under its stem; name a .json file"
        )
    with claim_file(output, siblings=siblings):
        report = Transcript()
        payload = _evaluate(cfg, names, seeds, output, report)
        report.save(transcript_path(output))
        return payload


def _evaluate(
    cfg: EvalConfig, names: list[str], seeds: list[int], output: Path, report: Transcript
) -> dict:
    sim = build_sim(cfg.sim_spec())
    report.print(f"layout {sim.layout.describe()}")
    names = policy_names(names)
    policies = policies_from_cfg(cfg, names, sim)
    compare_to, chosen = cfg.compare_to, None
    if compare_to == BEST:
        compare_to, chosen = _best_rule(cfg, sim, policies, report)
    if compare_to is not None and compare_to not in policies:
        raise ConfigError(
            f"compare_to={compare_to} is not an evaluated policy; "
            f"evaluated: {', '.join(policies)} (or compare_to=best: the best rule here)"
        )
    journal = _journal(cfg, names, output, policies, report)
    todo = sum(journal.get(name, seed) is None for name in policies for seed in seeds)
    try:
        # smoothing=0: the bar's ETA is the run's average rate, not the last policy's.
        with tqdm(
            # A horizon episode's decisions are known only at its end (num_tasks bounds them).
            total=None if sim.config.episode_mode == "horizon" else todo * sim.config.num_tasks,
            unit="dec",
            disable=not progress_shown(cfg.progress),
            leave=False,
            smoothing=0,
        ) as bar:
            estimate = TimeEstimate(announce=_to_stderr, show=bar.set_postfix_str)
            results = evaluate(
                sim, policies, seeds, on_decisions=bar.update, journal=journal, on_seed=estimate
            )
    except KeyboardInterrupt as exc:
        raise _interrupted(exc, journal) from None
    finally:
        journal.close()
    bound, bound_time = _lower_bound(cfg, sim, seeds, results, report)
    report.print(format_table(results, REFERENCE, lower_bound=bound, compare_to=compare_to))
    if sim.config.episode_mode == "horizon":
        report.print(
            throughput_table(
                results, sim.num_robots, int(sim.config.horizon or 0), (REFERENCE, compare_to)
            )
        )
    payload = results_payload(
        as_plain(cfg), seeds, results, REFERENCE, compare_to, bound, bound_time,
        best_rule=None if chosen is None else chosen.as_dict(),
    )  # fmt: skip
    path = write_json_atomic(output, payload)
    report.print(f"results: {path}")
    report.print(f"episodes: {write_episodes_csv(_csv(output), results, seeds)}")
    return payload


def _csv(output: Path) -> Path:
    """The per-episode table beside ``results.json``: ``results.csv``."""
    return output.with_name(f"{output.stem}.csv")


def _to_stderr(line: str) -> None:
    """A progress note (the time estimate): on stderr, above the bar if one is drawn."""
    tqdm.write(line, file=sys.stderr)


def _journal(
    cfg: EvalConfig,
    names: list[str],
    output: Path,
    policies: Mapping[str, object],
    report: Transcript,
) -> EpisodeJournal:
    """The episode journal beside ``output``: the setting with its input files as
    contents hashes, each learned policy's episodes keyed by its file's hash."""
    setting = with_file_digests({k: v for k, v in as_plain(cfg).items() if k not in NOT_SETTING})
    sources = {label: file_digest(path) for label, path in learned_files(cfg, names).items()}
    journal = EpisodeJournal(journal_path(output), setting, resume=cfg.resume, sources=sources)
    if journal.episodes:
        report.print(f"resume: {len(journal.episodes)} finished episodes from {journal.path}")
    for policy, (count, _) in journal.stale.items():
        if policy in policies:
            report.print(
                f"resume: the file of {policy} has changed since {count} of its episodes "
                "were journalled (another sha256): they run again"
            )
    return journal


def _best_rule(
    cfg: EvalConfig, sim: WarehouseSim, policies: dict[str, SimPolicy], report: Transcript
) -> tuple[str, BestRule]:
    """``compare_to=best``: the best rule of this setting, chosen on the selection seeds
    (played first, not journalled) and added to the evaluated policies if missing."""
    chosen = choose_best_rule(sim, DEFAULT_RULES, SELECTION_SEEDS, cfg.baselines)
    report.print(chosen.line())
    if chosen.name not in policies:
        spec = PolicySpec.rule(chosen.name, cfg.baselines)
        policies[chosen.name] = spec.build(sim, chosen.name, torch_threads=cfg.torch_threads)
    return chosen.name, chosen


def _interrupted(exc: KeyboardInterrupt, journal: EpisodeJournal) -> Interrupted:
    """Ctrl-C or SIGTERM: the one line says what is kept and how to go on."""
    signum = exc.signum if isinstance(exc, Interrupted) else signal.SIGINT
    if not journal.episodes:
        return Interrupted(signum=signum)
    return Interrupted(
        f"{journal.held()} kept in {journal.path}; run the same command with resume=true "
        "to continue",
        signum=signum,
    )


def _lower_bound(
    cfg: EvalConfig, sim: WarehouseSim, seeds: list[int], results: dict, report: Transcript
) -> tuple[list[float] | None, float | None]:
    """The TTD lower bound per seed and its cost, on request (drain mode only); adds
    each policy's ``gap_pct`` to ``results``."""
    if not cfg.lower_bound:
        return None, None
    if sim.config.episode_mode != "drain":
        report.print("lower bound: skipped (drain mode only)")
        return None, None
    start = time.perf_counter()
    bound = [ttd_lower_bound(sim, seed) for seed in seeds]
    bound_time = time.perf_counter() - start
    report.print(f"lower bound: {bound_time:.1f} s")
    for metrics in results.values():
        metrics["gap_pct"] = gap_to_bound(metrics["ttd"], bound)
    return bound, bound_time


main = hydra_entry("eval", run)

if __name__ == "__main__":
    main()
