"""Studies: policies x scenarios x seeds, run with a journal, rendered as a docs section.

A :class:`Study` is a list of :class:`Cell` s (one setting each: a scenario, the policies
evaluated there by table label, the seeds) and a renderer that turns their per-seed TTDs
into markdown. :func:`run_study` evaluates every cell (in worker processes if asked),
journals each finished episode in the output folder so a killed study resumes
(``resume=True``), and may take the rules' TTDs from a stored result instead of running
them again (``reuse``: a rule's episode depends on the seed only). The paper's tables
are studies (:mod:`benchmarks.studies`); ``python -m benchmarks.run`` runs them and can
rewrite their sections of docs/results.md and their data in benchmarks/data/.
"""

from __future__ import annotations

import json
import re
import sys
import time
from collections.abc import Callable, Iterator, Mapping, Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from rtaw_marl.errors import ConfigError
from rtaw_marl.evaluation.evaluate import evaluate
from rtaw_marl.evaluation.journal import EpisodeJournal, file_digest, with_file_digests
from rtaw_marl.policies.spec import PolicySpec
from rtaw_marl.scenarios import Scenario
from rtaw_marl.sim.builder import build_sim
from rtaw_marl.sim.inputs import seed_list
from rtaw_marl.utils.atomic import atomic_write

__all__ = [
    "Cell",
    "PolicyRef",
    "Study",
    "StudyResult",
    "Ttd",
    "checkpoint",
    "learned",
    "load_result",
    "replace_section",
    "rule",
    "run_study",
    "save_result",
]

#: Per-seed TTDs of each policy label in one cell.
Ttd = dict[str, list[float]]


#: What a table label stands for: the package's one policy resolver.
PolicyRef = PolicySpec


def rule(name: str, **params: Any) -> PolicyRef:
    """A rule of :data:`~rtaw_marl.policies.BASELINES` (``mpdm``, ``lookahead``, ...),
    with :class:`~rtaw_marl.policies.BaselinesConfig` parameters (checked now)."""
    return PolicySpec.rule(name, params)


def learned(name: str) -> PolicyRef:
    """A shipped learned policy (a pretrained registry name)."""
    return PolicySpec("pretrained", name)


def checkpoint(path: str | Path) -> PolicyRef:
    """A learned policy from a checkpoint file (``runs/x/checkpoints/best.pt``)."""
    return PolicySpec("checkpoint", str(path))


@dataclass(frozen=True, kw_only=True)
class Cell:
    """One setting of a study: a row of its tables.

    Attributes:
        key: The row's label (its key in the stored data).
        scenario: The setting.
        policies: Table label -> policy, in column order.
        seeds: Episode seeds.
    """

    key: str
    scenario: Scenario
    policies: Mapping[str, PolicyRef]
    seeds: tuple[int, ...]


@dataclass(frozen=True, kw_only=True)
class StudyResult:
    """What a study measured.

    Attributes:
        seeds: The seeds of every cell (a study's cells share them).
        ttd: Cell key -> label -> TTD per seed.
        seconds: Cell key -> label -> mean seconds per episode (labels run this time).
        extra: What a study with its own ``run`` measured besides (JSON-ready).
    """

    seeds: list[int]
    ttd: dict[str, Ttd]
    seconds: dict[str, dict[str, float]] = field(default_factory=dict)
    extra: dict[str, Any] = field(default_factory=dict)


@dataclass(frozen=True, kw_only=True)
class Study:
    """A named study.

    Attributes:
        name: Its name (``python -m benchmarks.run NAME``), its docs section and its data file.
        description: One line, for listings.
        cells: The cells for given seeds.
        render: Markdown of a result, given the stored results of the studies it
            pairs with (``{name: result}``).
        page: The docs page holding its ``<!-- BEGIN name -->`` section, if any.
        store: Whether ``benchmarks/data/<name>.json`` keeps its per-seed TTDs.
        default_seeds: Its seeds when none are given.
        pairs_with: Studies whose stored per-seed TTDs its tables pair with.
        run: Replaces :func:`run_study`'s episodes for a study that measures more than
            TTDs (``run(cells, output, workers, resume) -> StudyResult``; the decision
            analysis of docs/analysis.md); ``None``: every cell's policies are evaluated.
    """

    name: str
    description: str
    cells: Callable[[Sequence[int]], list[Cell]]
    render: Callable[[StudyResult, Mapping[str, StudyResult]], str]
    page: str | None = "results.md"
    store: bool = True
    default_seeds: tuple[int, ...] = tuple(range(20))
    pairs_with: tuple[str, ...] = ()
    run: Callable[[list[Cell], Path, int, bool], StudyResult] | None = None


def run_study(
    study: Study,
    seeds: Sequence[int],
    output: Path,
    workers: int = 1,
    resume: bool = False,
    reuse: StudyResult | None = None,
    reuse_learned: bool = False,
) -> StudyResult:
    """Evaluate every cell of ``study`` on ``seeds``.

    Args:
        study: The study.
        seeds: Episode seeds.
        output: The run folder: one episode journal per cell.
        workers: Evaluation processes (cells run in parallel).
        resume: Take the episodes already in the journals.
        reuse: A stored result whose rule TTDs are taken instead of run, where it holds
            the same seeds.
        reuse_learned: Take its learned policies' TTDs too (only valid while their
            checkpoints and the code that plays them are those of the stored run; a
            label missing from it is evaluated).

    Returns:
        The per-seed TTDs of every cell and label; a learned policy whose checkpoint
        is missing or does not load is left out, with one warning line on stderr.
    """
    seeds = seed_list(seeds)  # a seed given twice would count one episode twice
    cells = study.cells(seeds)
    if study.run is not None:
        return study.run(cells, output, workers, resume)
    kept = _reusable(reuse, list(seeds))
    jobs, ttd = [], {}
    for cell in cells:
        stored = kept.get(cell.key, {})
        ttd[cell.key] = {
            k: v
            for k, v in stored.items()
            if k in cell.policies and (reuse_learned or cell.policies[k].kind == "rule")
        }
        todo = {k: p for k, p in cell.policies.items() if k not in ttd[cell.key] and _ok(k, p)}
        if ttd[cell.key]:
            print(f"reused {cell.key}: {', '.join(ttd[cell.key])}", file=sys.stderr, flush=True)
        if todo:
            journal = output / f"{_slug(cell.key)}.episodes.jsonl"
            jobs.append((cell, todo, journal, resume))
    seconds: dict[str, dict[str, float]] = {}
    for key, measured, secs in _evaluated(jobs, workers):
        order = list(next(c for c in cells if c.key == key).policies)
        merged = {**ttd[key], **measured}
        ttd[key] = {k: merged[k] for k in order if k in merged}
        seconds[key] = secs
        print(f"done {key}", file=sys.stderr, flush=True)
    return StudyResult(seeds=seeds, ttd=ttd, seconds=seconds)


_WARNED: set[str] = set()


def _ok(label: str, ref: PolicyRef) -> bool:
    why = ref.loads()
    if why is not None and ref.name not in _WARNED:
        _WARNED.add(ref.name)
        print(f"warning: {label} ({ref.name}) skipped: {why}", file=sys.stderr)
    return why is None


def _reusable(reuse: StudyResult | None, seeds: list[int]) -> dict[str, Ttd]:
    """The stored TTDs of ``reuse`` when it holds ``seeds`` (the caller keeps rules')."""
    if reuse is None:
        return {}
    if reuse.seeds != seeds:
        print("warning: reuse: the stored result has other seeds; nothing reused", file=sys.stderr)
        return {}
    return reuse.ttd


Job = tuple[Cell, dict[str, PolicyRef], Path, bool]


def _evaluated(jobs: list[Job], workers: int) -> Iterator[tuple[str, Ttd, dict[str, float]]]:
    if workers <= 1 or len(jobs) <= 1:
        yield from map(_run_cell, jobs)
        return
    with ProcessPoolExecutor(max_workers=workers) as pool:
        yield from pool.map(_run_cell, jobs)


def _run_cell(job: Job) -> tuple[str, Ttd, dict[str, float]]:
    """One cell's policies on its seeds, journalled episode by episode."""
    cell, todo, path, resume = job
    sim = build_sim(cell.scenario.spec())
    policies = {label: ref.build(sim, label) for label, ref in todo.items()}
    # Files by contents: a map or checkpoint replaced at the same path is not replayed.
    setting = with_file_digests(
        {
            "cell": cell.key,
            "sim": cell.scenario.spec().as_dict(),
            "policies": {k: [p.kind, p.name, dict(p.params)] for k, p in todo.items()},
        }
    )
    sources = {k: file_digest(p.path()) for k, p in todo.items() if p.kind != "rule"}
    path.parent.mkdir(parents=True, exist_ok=True)
    journal = EpisodeJournal(path, setting, resume=resume, sources=sources)
    try:
        res = evaluate(sim, policies, cell.seeds, journal=journal)
    finally:
        journal.close()
    ttd = {k: v["ttd"] for k, v in res.items()}
    return cell.key, ttd, {k: float(np.mean(v["wall_time_s"])) for k, v in res.items()}


def _slug(key: str) -> str:
    return re.sub(r"[^A-Za-z0-9]+", "_", key).strip("_")


# --------------------------------------------------------------------------- files
def load_result(path: Path) -> StudyResult | None:
    """A stored result (``{"seeds": [...], "rows": {key: {label: [ttd]}}}``), or None."""
    if not path.is_file():
        return None
    payload = json.loads(path.read_text())
    return StudyResult(seeds=payload["seeds"], ttd=payload["rows"])


def save_result(path: Path, result: StudyResult) -> None:
    """Store the per-seed TTDs (atomically)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    text = json.dumps({"seeds": result.seeds, "rows": result.ttd}, indent=1) + "\n"
    atomic_write(path, lambda fh: fh.write(text.encode()))


def replace_section(page: Path, name: str, body: str) -> None:
    """Replace the text between ``<!-- BEGIN name -->`` and ``<!-- END name -->``.

    Raises:
        ConfigError: The page or its markers are missing.
    """
    text = page.read_text() if page.is_file() else ""
    begin, end = f"<!-- BEGIN {name} -->", f"<!-- END {name} -->"
    if begin not in text or end not in text:
        raise ConfigError(f"{page} has no {begin} ... {end} markers")
    head, rest = text.split(begin, 1)
    _, tail = rest.split(end, 1)
    stamp = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())
    out = f"{head}{begin}\n_Generated {stamp}._\n\n{body}\n{end}{tail}"
    atomic_write(page, lambda fh: fh.write(out.encode()))
