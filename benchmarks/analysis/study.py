"""The ``analysis`` study: learned policies' own trajectories on Table I's rows, probed.

Each cell is a Table I row in ``drain`` mode with MPDM (its own episodes: the TTD
baseline), the learned policies and ``lookahead``; every policy but MPDM plays its own
greedy episodes through :func:`~benchmarks.analysis.decisions.play`. The
result's ``extra`` holds each policy's :class:`Summary` (``summaries``), the policies
that did not load (``skipped``), lookahead's horizon and the command that made it;
:func:`render` turns it into the generated section of docs/analysis.md.
"""

from __future__ import annotations

import dataclasses
import sys
import time
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks.analysis.decisions import LOOKAHEAD, Decision, play
from benchmarks.analysis.page import section
from benchmarks.analysis.summary import Summary, summarise
from benchmarks.study import (
    Cell,
    PolicyRef,
    Study,
    StudyResult,
    checkpoint,
    learned,
    rule,
)
from benchmarks.tables import LEARNED
from rtaw_marl.errors import ConfigError, unknown_name
from rtaw_marl.evaluation.evaluate import run_episode
from rtaw_marl.policies import make_baseline
from rtaw_marl.scenarios import EVAL_SEEDS, ROWS, SCENARIOS, TABLE1_ROBOTS, Scenario
from rtaw_marl.sim.builder import build_sim

__all__ = ["ANALYSIS", "DEFAULT_POLICIES", "DEFAULT_ROWS", "analyse", "analysis_study", "render"]

#: Rows (:data:`rtaw_marl.scenarios.ROWS`) and learned policies of docs/analysis.md.
DEFAULT_ROWS = ("C", "direct")
DEFAULT_POLICIES = ("RTAW+", "RTAW")
#: The TTD baseline of every cell (its own episodes, not probed).
BASELINE = "MPDM"
COMMAND = "python -m benchmarks.run analysis --write"
_ROW_OF = {name: row for row, name in ROWS.items()}


def row_label(s: Scenario) -> str:
    """The row's label: the scenario's title, without Table I's first robot count
    (``A* layout C``; ``A* layout C, M=100`` stays)."""
    return s.title.removesuffix(f", M={TABLE1_ROBOTS[0]}")


def policy_label(name: str, ref: PolicyRef) -> str:
    """``RTAW+ (C_astar_m10_long_plus)`` for a row's own policy, else ``name``."""
    return f"{name} ({ref.name})" if ref.kind == "pretrained" and ref.name != name else name


def row_cell(
    row: str, names: Sequence[str], checkpoints: Sequence[str], seeds: Sequence[int]
) -> Cell:
    """One row's cell: MPDM, the learned policies (``RTAW``/``RTAW+``: the row's own;
    else a registry entry), the checkpoint files, then lookahead."""
    s = SCENARIOS[ROWS[row]].with_sim(episode_mode="drain")
    refs = {BASELINE: rule("mpdm")}
    for name in names:
        refs[name] = learned(s.policies[name] if name in LEARNED else name)
    refs.update({str(path): checkpoint(path) for path in checkpoints})
    refs[LOOKAHEAD] = rule(LOOKAHEAD)
    return Cell(key=row_label(s), scenario=s, policies=refs, seeds=tuple(seeds))


# --------------------------------------------------------------------------- run
Job = tuple[Cell, str]
Played = tuple[list[Decision] | None, list[float], float]


def _play(job: Job) -> Played:
    """One policy of one cell on its seeds: its decisions (None for the baseline, which
    plays plain episodes), its TTD per seed, seconds per episode."""
    cell, name = job
    sim = build_sim(cell.scenario.spec())
    label = policy_label(name, cell.policies[name])
    policy = cell.policies[name].build(sim, label)
    start = time.perf_counter()
    if name == BASELINE:
        decisions, ttds = None, [run_episode(sim, policy, s).ttd for s in cell.seeds]
    else:
        decisions, ttds = play(sim, policy, cell.seeds)
    took = time.perf_counter() - start
    print(f"done {cell.key}: {label} ({took:.0f} s)", file=sys.stderr, flush=True)
    return decisions, ttds, took / len(cell.seeds)


def _played(jobs: list[Job], workers: int) -> list[Played]:
    if workers <= 1 or len(jobs) <= 1:
        return [_play(j) for j in jobs]
    with ProcessPoolExecutor(max_workers=workers) as pool:
        return list(pool.map(_play, jobs))


def _jobs(cells: Sequence[Cell]) -> tuple[list[Job], list[str]]:
    """Every (cell, policy) to play, and the policies that do not load (warned about)."""
    jobs, skipped = [], []
    for cell in cells:
        for name, ref in cell.policies.items():
            why = ref.loads()
            if why is None:
                jobs.append((cell, name))
                continue
            label = policy_label(name, ref)
            print(f"warning: {cell.key}: {label} skipped: {why}", file=sys.stderr, flush=True)
            skipped.append(f"{label} on {cell.key}")
    return jobs, skipped


def _summaries(cells: Sequence[Cell], played: dict[tuple[str, str], Played]) -> list[Summary]:
    """Each played policy's summary (row by row, in each cell's policy order)."""
    out = []
    for cell in cells:
        mpdm_ttd = float(np.mean(played[cell.key, BASELINE][1]))
        short = _ROW_OF.get(cell.scenario.name, cell.key).capitalize()
        for name, ref in cell.policies.items():
            decisions, ttds, _ = played.get((cell.key, name), (None, [], 0.0))
            if decisions is not None:
                out.append(summarise(decisions, ttds, mpdm_ttd, row=cell.key, short=short,
                                     name=name, policy=policy_label(name, ref)))  # fmt: skip
    return out


def run(
    cells: list[Cell],
    output: Path,
    workers: int = 1,
    resume: bool = False,
    *,
    made_with: Callable[[list[int]], str] | None = None,
) -> StudyResult:
    """Play every cell's policies and summarise their decisions (``Study.run``).

    ``output`` and ``resume`` are not used: nothing is journalled, a killed run starts
    over. ``made_with(seeds)`` is the command recorded in the page.
    """
    jobs, skipped = _jobs(cells)
    played = dict(zip(((c.key, n) for c, n in jobs), _played(jobs, workers), strict=True))
    ttd = {c.key: {n: played[c.key, n][1] for n in c.policies if (c.key, n) in played}
           for c in cells}  # fmt: skip
    seconds = {c.key: {n: played[c.key, n][2] for n in ttd[c.key]} for c in cells}
    summaries = _summaries(cells, played)
    seeds = list(cells[0].seeds) if cells else []
    extra: dict[str, Any] = {
        "summaries": [dataclasses.asdict(s) for s in summaries],
        "skipped": skipped,
        "horizon": make_baseline(LOOKAHEAD).horizon,
        "command": (made_with or _command)(seeds),
    }
    return StudyResult(seeds=seeds, ttd=ttd, seconds=seconds, extra=extra)


def render(result: StudyResult, _: object = None) -> str:
    """The generated section of docs/analysis.md (``Study.render``); a result without
    :func:`run`'s ``extra`` (TTDs only) gives empty tables."""
    x = result.extra
    summaries = [Summary(**s) for s in x.get("summaries", [])]
    horizon = x.get("horizon", make_baseline(LOOKAHEAD).horizon)
    command = x.get("command", _command(result.seeds))
    return section(summaries, result.seeds, horizon, command, x.get("skipped", []))


# --------------------------------------------------------------------------- entries
def _command(seeds: Sequence[int]) -> str:
    return COMMAND if list(seeds) == list(EVAL_SEEDS) else f"{COMMAND} seeds={_list(seeds)}"


def _list(values: Sequence[Any]) -> str:
    return "[" + ",".join(map(str, values)) + "]"


def analysis_study(
    rows: Sequence[str] = DEFAULT_ROWS,
    policies: Sequence[str] | None = None,
    checkpoints: Sequence[str | Path] = (),
) -> Study:
    """The analysis over ``rows`` (:data:`~rtaw_marl.scenarios.ROWS` names).

    Args:
        rows: Table I rows, in page order.
        policies: Registry entries, used as is on every row, or ``RTAW`` / ``RTAW+``:
            each row's own shipped policy. ``None``: :data:`DEFAULT_POLICIES`, or none
            when ``checkpoints`` are given.
        checkpoints: Checkpoint files, analysed on every row after ``policies``.

    Raises:
        ConfigError: An unknown row, or nothing to analyse.
    """
    for row in rows:
        if row not in ROWS:
            raise unknown_name("row", row, list(ROWS))
    names = list(DEFAULT_POLICIES if policies is None and not checkpoints else policies or ())
    paths = [str(p) for p in checkpoints]
    if not rows or not (names or paths):
        raise ConfigError("analysis: give at least one row and one policy or checkpoint")
    custom = (tuple(rows), tuple(names), paths) != (DEFAULT_ROWS, DEFAULT_POLICIES, [])

    def made_with(seeds: Sequence[int]) -> str:
        if not custom:
            return _command(seeds)
        return (f"analyse(seeds={_list(seeds)}, rows={list(rows)}, policies={names}, "
                f"checkpoints={paths})  # benchmarks.analysis")  # fmt: skip

    return Study(
        name="analysis",
        description="What the learned policies do differently (decision statistics)",
        cells=lambda seeds: [row_cell(r, names, paths, seeds) for r in rows],
        render=render,
        page="analysis.md",
        store=False,
        default_seeds=EVAL_SEEDS,
        run=partial(run, made_with=made_with),
    )


#: The study of docs/analysis.md (``python -m benchmarks.run analysis``).
ANALYSIS = analysis_study()


def analyse(
    seeds: Sequence[int] = EVAL_SEEDS,
    rows: Sequence[str] = DEFAULT_ROWS,
    policies: Sequence[str] | None = None,
    checkpoints: Sequence[str | Path] = (),
    workers: int = 1,
) -> tuple[StudyResult, str]:
    """Run the analysis from Python (arguments as :func:`analysis_study`'s).

    Returns:
        The result and its markdown (the generated section of docs/analysis.md).
    """
    if not seeds:
        raise ConfigError("analysis: give at least one seed")
    study = analysis_study(rows, policies, checkpoints)
    result = study.run(study.cells(list(seeds)), Path("."), workers, False)
    return result, study.render(result, {})
