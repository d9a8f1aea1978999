"""The generalist's studies: one set of weights on every table row and on settings no
policy trained on (``python -m benchmarks.run generalist_table1`` etc.).

* ``generalist_table1``, ``generalist_table2``: the generalist alone on Table I's rows
  (both episode modes) and Table II's, on the evaluation seeds; its tables pair each of
  its episodes with the stored tables' rules and specialists on the same seed.
* ``generalist_unseen``: robot counts between and beyond the mix's (3, 30, 150, 300 on
  layout C; 2,000 on the 256x256 warehouse), the MovingAI warehouse map and LoRR's
  ``warehouse_large`` (1,000 and 10,000 robots; maps from ``../shared/maps``), with
  MPDM, ``lookahead``, the nearest specialist and the generalist; and the mix member
  that selected its checkpoint, on the evaluation seeds (its held-out gain).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

from benchmarks.study import Cell, PolicyRef, Study, StudyResult, learned, rule
from benchmarks.tables import (
    BEST,
    TABLE1,
    TABLE2,
    compare,
    mean_cell,
    percent,
    pooled,
    pooled_share,
    share,
    stored_best,
    wins,
    with_best,
)
from rtaw_marl.evaluation.report import markdown_table
from rtaw_marl.scenarios import SCENARIOS, Scenario

__all__ = [
    "GENERALIST_STUDIES",
    "HOLDOUT_ROW",
    "SHARED_MAPS",
    "custom_scenario",
    "shared_map",
    "unseen_settings",
]

#: The generalist's label in the tables, and its shipped name.
LABEL, NAME = "generalist", "generalist_plus"
#: The maps the unseen settings read (relative to the repository root).
SHARED_MAPS = Path("..") / "shared" / "maps"
#: Each row's comparisons: the generalist against these.
AGAINST = ("MPDM", "lookahead", BEST, "RTAW+")
#: The unseen settings that are rows of the search tables' hold-out grid, under its names
#: (the same scenario and seeds: the same episodes); their best rule is stored there.
HOLDOUT_ROW = {
    "layout C, queue of 20, M=30": "layout C, queue 20, M=30",
    "LoRR warehouse_large, M=1000": "LoRR warehouse_large, M=1000, paper",
}


def _alone(s: Scenario, key: str, seeds: Sequence[int]) -> Cell:
    return Cell(key=key, scenario=s, policies={LABEL: learned(NAME)}, seeds=tuple(seeds))


def _table1_cells(seeds: Sequence[int]) -> list[Cell]:
    return [
        _alone(s, f"{mode}|{s.title}", seeds)
        for mode in ("paper", "drain")
        for s in (SCENARIOS[n].with_sim(episode_mode=mode) for n in TABLE1)
    ]


def _table2_cells(seeds: Sequence[int]) -> list[Cell]:
    return [_alone(SCENARIOS[n], SCENARIOS[n].title, seeds) for n in TABLE2]


def _paired(result: StudyResult, stored: Mapping[str, StudyResult], name: str) -> dict:
    """The stored rows of ``name`` (``table1_<mode>`` for a ``mode|`` key) with the
    generalist's TTDs added, on the seeds both hold."""
    rows = {}
    for key, own in result.ttd.items():
        mode, _, title = key.rpartition("|")
        saved = stored[f"{name}_{mode}" if mode else name]
        n = min(len(result.seeds), len(saved.seeds))
        if list(result.seeds[:n]) != list(saved.seeds[:n]):
            raise ValueError(f"{key}: the stored {name} seeds differ from this run's")
        rows[key] = {**{k: v[:n] for k, v in saved.ttd[title].items()}, LABEL: own[LABEL][:n]}
    return rows


def _rows_table(
    rows: Mapping[str, Mapping[str, Sequence[float]]], best: Mapping[str, str], shares: bool
) -> str:
    cols = [c for c in ("MPDM", "lookahead", "RTAW+", LABEL) if any(c in t for t in rows.values())]
    head = ["setting", *cols, "best rule (seeds 1000-1019)"]
    head += [f"{LABEL} vs {b}" for b in AGAINST]
    if shares:
        head.append(f"hindsight share: RTAW+ / {LABEL}")
    table = []
    for key, t in rows.items():
        cells = [key.replace("|", ", "), *(mean_cell(t, c) for c in cols), best.get(key, "-")]
        cells += [compare(t, b, LABEL) for b in AGAINST]
        if shares:
            cells.append(f"{share(t, 'RTAW+')} / {share(t, LABEL)}")
        table.append(cells)
    return markdown_table(head, table)


def _pooled_lines(rows: Sequence[Mapping[str, Sequence[float]]], what: str) -> list[str]:
    lines = [f"- {LABEL} vs {b}, pooled over {what}: {pooled(rows, b, LABEL)}" for b in AGAINST]
    lines.append(
        f"- RTAW+ (specialists) vs lookahead, pooled: {pooled(rows, 'lookahead', 'RTAW+')}"
    )
    lines += [wins(rows, b, LABEL) for b in ("lookahead", "RTAW+")]
    return lines


def _table1(result: StudyResult, stored: Mapping[str, StudyResult]) -> str:
    rows, best = with_best(_paired(result, stored, "table1"), stored_best("table1"))
    parts = [_rows_table(rows, best, shares=True), ""]
    for mode in ("paper", "drain"):
        part = [t for k, t in rows.items() if k.startswith(f"{mode}|")]
        parts += _pooled_lines(part, f"Table I, {mode} mode")
        parts.append(
            f"- hindsight share, pooled ({mode}): RTAW+ {percent(pooled_share(part, 'RTAW+'))}"
            f", {LABEL} {percent(pooled_share(part, LABEL))}"
        )
    every = list(rows.values())
    parts += _pooled_lines(every, "both modes")
    parts.append(f"- {LABEL}'s hindsight share, both modes: {percent(pooled_share(every, LABEL))}")
    return "\n".join(parts)


def _table2(result: StudyResult, stored: Mapping[str, StudyResult]) -> str:
    rows, best = with_best(_paired(result, stored, "table2"), stored_best("table2"))
    return "\n".join(
        [_rows_table(rows, best, shares=False), "", *_pooled_lines(list(rows.values()), "Table II")]
    )


def shared_map(*parts: str) -> dict[str, str]:
    """The layout option of a map file under ``../shared/maps``."""
    return {"name": "file", "path": str(SHARED_MAPS.joinpath(*parts))}


def unseen_settings() -> dict[str, tuple[Scenario, str]]:
    """The unseen settings: key -> (scenario, the nearest specialist's shipped name)."""
    c, big = SCENARIOS["C_astar_m10"], SCENARIOS["C256_astar_m1000_random"]
    movingai = shared_map("movingai", "warehouse-10-20-10-2-1.map")
    lorr = shared_map("lorr", "maps", "warehouse_large.map")
    out: dict[str, tuple[Scenario, str]] = {}
    for m in (3, 30, 150, 300):
        out[f"layout C, M={m}"] = (
            c.with_sim(num_robots=m),
            "C_astar_m10_long_plus" if m < 50 else "C_astar_m100_long_plus",
        )
    out["layout C, queue of 20, M=30"] = (
        c.with_sim(num_robots=30, queue_len=20),
        "C_astar_m10_long_plus",
    )
    out["256x256 C, M=2000"] = (big.with_sim(num_robots=2000), "C256_astar_m500_random_plus")
    for m in (10, 100):
        s = custom_scenario(f"movingai_m{m}", movingai, {"num_robots": m, "num_tasks": 500})
        out[f"MovingAI warehouse-10-20-10-2-1, M={m}"] = (s, "C_astar_m100_long_plus")
    # The setting that selected the generalist's checkpoint (a mix member), on the
    # evaluation seeds: its selection-seed gain against its held-out gain.
    out["selection setting: layout A, M=200, paper (trained on)"] = (
        SCENARIOS["A_astar_m100"].with_sim(num_robots=200, episode_mode="paper"),
        "A_astar_m100_long_plus",
    )
    for m, tasks in ((1000, 2000), (10_000, 1000)):
        sim = {"num_robots": m, "num_tasks": tasks, "episode_mode": "paper"}
        out[f"LoRR warehouse_large, M={m}"] = (
            custom_scenario(f"lorr_m{m}", lorr, sim),
            "C256_astar_m500_random_plus",
        )
    return out


def custom_scenario(name: str, layout: dict, sim: dict) -> Scenario:
    """A scenario on ``layout`` with A* and random tasks (``sim``: its simulator keys)."""
    return Scenario(
        name=name, title=name, description=name, layout=layout, navigator="astar",
        tasks="random", sim=sim,
    )  # fmt: skip


def _unseen_cells(seeds: Sequence[int]) -> list[Cell]:
    cells = []
    for key, (s, specialist) in unseen_settings().items():
        policies: dict[str, PolicyRef] = {
            "MPDM": rule("mpdm"), "lookahead": rule("lookahead"),
            "RTAW+": learned(specialist), LABEL: learned(NAME),
        }  # fmt: skip
        cells.append(Cell(key=key, scenario=s, policies=policies, seeds=tuple(seeds)))
    return cells


def _unseen_render(result: StudyResult, _: Mapping[str, StudyResult]) -> str:
    specialists = "\n".join(f"- {k}: RTAW+ = `{v[1]}`" for k, v in unseen_settings().items())
    rows, best = with_best(
        result.ttd, stored_best("holdout", "unseen"), key=lambda k: HOLDOUT_ROW.get(k, k)
    )
    return "\n".join(
        [
            _rows_table(rows, best, shares=False), "", *_pooled_lines(list(rows.values()), "them"),
            "", "The specialist of each row (the nearest shipped RTAW+):", "", specialists,
        ]
    )  # fmt: skip


#: The generalist's studies, by name.
GENERALIST_STUDIES = (
    Study(name="generalist_table1", description="The generalist on Table I (both modes)",
          cells=_table1_cells, render=_table1, pairs_with=("table1_paper", "table1_drain")),
    Study(name="generalist_table2", description="The generalist on Table II",
          cells=_table2_cells, render=_table2, pairs_with=("table2",)),
    Study(name="generalist_unseen", description="The generalist on unseen fleets and maps",
          cells=_unseen_cells, render=_unseen_render),
)  # fmt: skip
