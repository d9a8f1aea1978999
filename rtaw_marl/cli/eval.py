"""``rtaw-eval``: evaluate policies on seeded episodes and write ``results.json``.

Examples::

    rtaw-eval scenario=poc policy=[mpdm,rbts]
    rtaw-eval env.num_robots=100 env.num_tasks=500 navigator=astar layout=open seeds=[0,1,2]
    rtaw-eval --multirun env.num_robots=10,100 navigator=direct,astar
    rtaw-eval policy=[mpdm,rbts,checkpoint] checkpoint=[runs/a/best.pt,runs/b/best.pt]
    rtaw-eval policy=[mpdm,rbts,hindsight] compare_to=rbts lower_bound=true
    rtaw-eval ... output=runs/big/results.json resume=true   # after a kill: skip finished episodes
"""

from __future__ import annotations

import time
from pathlib import Path

from hydra.core.hydra_config import HydraConfig
from omegaconf import DictConfig
from tqdm import tqdm

from rtaw_marl.cli.common import (
    as_list,
    exit_on_user_error,
    hydra_entry,
    policies_from_cfg,
    typed,
)
from rtaw_marl.config import as_plain
from rtaw_marl.errors import ConfigError
from rtaw_marl.evaluation import comparisons, evaluate, format_table, write_json_atomic
from rtaw_marl.evaluation.config import EvalConfig
from rtaw_marl.evaluation.journal import EpisodeJournal, journal_path
from rtaw_marl.evaluation.lower_bound import ttd_lower_bound
from rtaw_marl.evaluation.report import gap_to_bound
from rtaw_marl.sim.builder import build_sim
from rtaw_marl.sim.core import WarehouseSim
from rtaw_marl.utils.runs import claim_file

#: The main baseline every policy is compared with (when it is evaluated).
REFERENCE = "mpdm"


#: Options that do not change an episode's outcome: a resumed evaluation may differ in
#: them (policies and seeds are matched episode by episode).
_NOT_SETTING = (
    "policy", "checkpoint", "pretrained", "seeds", "compare_to", "lower_bound", "output",
    "resume", "progress", "torch_threads",
)  # fmt: skip


@exit_on_user_error
def run(cfg: DictConfig | EvalConfig) -> dict:
    """Evaluate ``cfg.policy`` on ``cfg.seeds`` and write the results; returns them."""
    cfg = typed(cfg)
    names = as_list(cfg.policy)
    seeds = [cfg.seeds] if isinstance(cfg.seeds, int) else list(cfg.seeds)
    if not names:
        raise ConfigError("policy must name at least one policy")
    if not seeds or not all(isinstance(s, int) and not isinstance(s, bool) for s in seeds):
        raise ConfigError(f"seeds must be a non-empty list of integers, got {seeds}")
    output = Path(cfg.output or f"{HydraConfig.get().runtime.output_dir}/results.json")
    # Checked and held before any work, so a bad path does not cost a whole evaluation
    # and two runs never write the same results.
    with claim_file(output):
        return _evaluate(cfg, names, seeds, output)


def _evaluate(cfg: EvalConfig, names: list[str], seeds: list[int], output: Path) -> dict:
    sim = build_sim(cfg.sim_spec())
    print(f"layout {sim.layout.describe()}")
    policies = policies_from_cfg(cfg, names, sim)
    if cfg.compare_to is not None and cfg.compare_to not in policies:
        raise ConfigError(
            f"compare_to={cfg.compare_to} is not an evaluated policy; "
            f"evaluated: {', '.join(policies)}"
        )
    setting = {k: v for k, v in as_plain(cfg).items() if k not in _NOT_SETTING}
    journal = EpisodeJournal(journal_path(output), setting, resume=cfg.resume)
    if journal.episodes:
        print(f"resume: {len(journal.episodes)} finished episodes from {journal.path}")
    total = len(policies) * len(seeds) * sim.config.num_tasks
    try:
        with tqdm(total=total, unit="dec", disable=not cfg.progress, leave=False) as bar:
            results = evaluate(sim, policies, seeds, on_decisions=bar.update, journal=journal)
    finally:
        journal.close()
    bound, bound_time = _lower_bound(cfg, sim, seeds, results)
    print(format_table(results, REFERENCE, lower_bound=bound, compare_to=cfg.compare_to))
    payload = {
        "config": as_plain(cfg),
        "seeds": seeds,
        "lower_bound": bound,
        "lower_bound_time_s": bound_time,
        "policies": results,
        "comparisons": comparisons(results, REFERENCE, compare_to=cfg.compare_to),
    }
    path = write_json_atomic(output, payload)
    print(f"results: {path}")
    return payload


def _lower_bound(
    cfg: EvalConfig, sim: WarehouseSim, seeds: list[int], results: dict
) -> tuple[list[float] | None, float | None]:
    """The TTD lower bound per seed and its cost, on request (drain mode only); adds
    each policy's ``gap_pct`` to ``results``."""
    if not cfg.lower_bound:
        return None, None
    if sim.config.episode_mode != "drain":
        print("lower bound: skipped (drain mode only)")
        return None, None
    start = time.perf_counter()
    bound = [ttd_lower_bound(sim, seed) for seed in seeds]
    bound_time = time.perf_counter() - start
    print(f"lower bound: {bound_time:.1f} s")
    for metrics in results.values():
        metrics["gap_pct"] = gap_to_bound(metrics["ttd"], bound)
    return bound, bound_time


main = hydra_entry("eval", run)

if __name__ == "__main__":
    main()
