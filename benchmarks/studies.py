"""The paper's tables and the project's checks as studies (``python -m benchmarks.run NAME``).

Every table of docs/results.md, and the budget table of docs/training.md, is one
:class:`~benchmarks.study.Study` here, over the scenarios of
:mod:`rtaw_marl.scenarios`. The evaluation seeds are 0-19 (``seeds=`` takes fewer); the
shipped policies were trained and selected on other seeds. ``lookahead_horizon`` runs on
the selection seeds 1000-1019 on purpose: it checks the rule's parameter the tables use.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping, Sequence

from benchmarks.analysis import ANALYSIS
from benchmarks.generalist import GENERALIST_STUDIES
from benchmarks.study import Cell, PolicyRef, Study, StudyResult, learned, rule
from benchmarks.tables import (
    BEST,
    LEARNED,
    SHARES,
    TABLE1,
    TABLE2,
    compare,
    mean_cell,
    percent,
    pooled,
    pooled_share,
    section,
    share,
    share_line,
    shares,
    stored_best,
    vs,
    with_best,
)
from rtaw_marl.errors import lookup
from rtaw_marl.evaluation.report import markdown_table
from rtaw_marl.scenarios import SCENARIOS, Scenario

__all__ = ["STUDIES", "study"]

#: The rules of every table, by label.
RULES: dict[str, PolicyRef] = {
    "MPDM": rule("mpdm"),
    "RBTS": rule("rbts"),
    "lookahead": rule("lookahead"),
    "hungarian": rule("hungarian"),
    "hindsight": rule("hindsight"),
}


def _policies(
    s: Scenario, hindsight: bool = True, shipped: Mapping[str, str] | None = None
) -> dict[str, PolicyRef]:
    rules = {k: v for k, v in RULES.items() if hindsight or k != "hindsight"}
    names = s.policies if shipped is None else shipped
    return {**rules, **{label: learned(names[label]) for label in LEARNED}}


def _table1_cells(mode: str) -> Callable[[Sequence[int]], list[Cell]]:
    def cells(seeds: Sequence[int]) -> list[Cell]:
        out = []
        for name in TABLE1:
            s = SCENARIOS[name].with_sim(episode_mode=mode)
            out.append(Cell(key=s.title, scenario=s, policies=_policies(s), seeds=tuple(seeds)))
        return out

    return cells


def _table1_section(mode: str) -> Callable[[StudyResult, Mapping[str, StudyResult]], str]:
    """Table I in ``mode``, against each row's best rule (``search_table1.json``)."""

    def render(result: StudyResult, _: Mapping[str, StudyResult]) -> str:
        rows, best = with_best(result.ttd, stored_best("table1"), key=lambda k: f"{mode}|{k}")
        return section(rows, best)

    return render


def _table2_cells(seeds: Sequence[int]) -> list[Cell]:
    cells = []
    for name in TABLE2:
        s = SCENARIOS[name]
        cells.append(
            Cell(
                key=s.title, scenario=s, policies=_policies(s, hindsight=False), seeds=tuple(seeds)
            )
        )
    return cells


def _table2(result: StudyResult, _: Mapping[str, StudyResult]) -> str:
    wall = ["", "Seconds per episode (mean over seeds, policies evaluated in this run):", ""]
    for key in result.ttd:
        secs = result.seconds.get(key, {})
        wall.append(f"- {key}: " + ", ".join(f"{k} {v:.1f}" for k, v in secs.items()))
    rows, best = with_best(result.ttd, stored_best("table2"))
    return section(rows, best) + "\n" + "\n".join(wall)


def _table2_hindsight_cells(seeds: Sequence[int]) -> list[Cell]:
    return [
        Cell(
            key=SCENARIOS[n].title,
            scenario=SCENARIOS[n],
            policies={"hindsight": RULES["hindsight"]},
            seeds=tuple(seeds),
        )
        for n in TABLE2
    ]


def _table2_hindsight(result: StudyResult, stored: Mapping[str, StudyResult]) -> str:
    """The hindsight reference on Table II's first seeds beside the stored Table II."""
    saved, n = stored["table2"].ttd, len(result.seeds)
    cols = ("MPDM", "lookahead", *LEARNED, "hindsight")
    head = ["setting", "seeds", *cols, "hindsight share: " + " / ".join(SHARES)]
    rows, ttds = [], []
    for key, res in result.ttd.items():
        row = {k: v[:n] for k, v in saved[key].items() if k != "hindsight"}
        row["hindsight"] = res["hindsight"]
        ttds.append(row)
        seeds = f"{result.seeds[0]}-{result.seeds[-1]}"
        rows.append([key, seeds, *(mean_cell(row, p) for p in cols), shares(row)])
    return markdown_table(head, rows) + "\n\n" + share_line(ttds)


PRESETS = "ABCDE"


def _transfer_cells(seeds: Sequence[int]) -> list[Cell]:
    """Each layout's 10-robot policies (409,600 frames) on every layout, with MPDM."""
    cells = []
    for p in PRESETS:
        s = SCENARIOS[f"{p}_astar_m10"]
        cells.append(
            Cell(
                key=f"MPDM on {p}", scenario=s, policies={"MPDM": RULES["MPDM"]}, seeds=tuple(seeds)
            )
        )
        for t in PRESETS:
            trained = SCENARIOS[f"{t}_astar_m10"]
            policies = {"RTAW": learned(trained.name), "RTAW+": learned(f"{trained.name}_plus")}
            cells.append(Cell(key=f"{t} on {p}", scenario=s, policies=policies, seeds=tuple(seeds)))
    return cells


def _transfer(result: StudyResult, _: Mapping[str, StudyResult]) -> str:
    ttd = {
        (t, p): {**result.ttd[f"MPDM on {p}"], **result.ttd[f"{t} on {p}"]}
        for t in PRESETS
        for p in PRESETS
    }
    parts = []
    for label in LEARNED:
        head = [f"{label}: trained on \\ evaluated on", *PRESETS]
        rows = [[t, *(compare(ttd[t, p], "MPDM", label) for p in PRESETS)] for t in PRESETS]
        own = [v for (t, p), v in ttd.items() if t == p]
        other = [v for (t, p), v in ttd.items() if t != p]
        parts.append(
            markdown_table(head, rows) + f"\n\n- {label} vs MPDM, pooled: own layout "
            f"{pooled(own, 'MPDM', label)}; other layouts {pooled(other, 'MPDM', label)}"
        )
    return "\n\n".join(parts)


NAVIGATORS = ("astar", "sipp", "cbs")


def _navigator_cells(seeds: Sequence[int]) -> list[Cell]:
    """10 robots, 50 tasks, no noise, on A-E with A*, SIPP and CBS execution; the
    A*-trained 10-robot policies (409,600 frames)."""
    cells = []
    for nav in NAVIGATORS:
        for p in PRESETS:
            base = SCENARIOS[f"{p}_astar_m10"]
            s = dataclasses.replace(base, navigator=nav).with_sim(
                num_tasks=50, noise_mean=0.0, noise_var=0.0
            )
            shipped = {"RTAW": base.name, "RTAW+": f"{base.name}_plus"}
            cells.append(
                Cell(
                    key=f"{p}, {nav}",
                    scenario=s,
                    policies=_policies(s, shipped=shipped),
                    seeds=tuple(seeds),
                )
            )
    return cells


#: The pooled lines per navigator, (policy, baseline).
NAV_POOLED = [("RTAW+", "MPDM"), ("RTAW+", "RBTS"), ("RTAW+", "lookahead"),
              ("RTAW", "MPDM"), ("RTAW", "RBTS"), ("lookahead", "MPDM")]  # fmt: skip


def _navigators(result: StudyResult, _: Mapping[str, StudyResult]) -> str:
    lines = []
    for nav in NAVIGATORS:
        rows = [result.ttd[f"{p}, {nav}"] for p in PRESETS]
        parts = [f"{o} vs {b} {pooled(rows, b, o)}" for o, b in NAV_POOLED]
        lines.append(f"- {nav}, pooled over A-E: " + "; ".join(parts))
    return section(result.ttd) + "\n" + "\n".join(lines)


#: The 409,600-frame bases of Table I's columns, by their label in the paired rows.
BASE = {"RTAW": "RTAW 1x", "RTAW+": "RTAW+ 1x"}


def _budget_cells(seeds: Sequence[int]) -> list[Cell]:
    cells = []
    for mode in ("paper", "drain"):
        for name in TABLE1:
            s = SCENARIOS[name].with_sim(episode_mode=mode)
            policies = {"RTAW": learned(name), "RTAW+": learned(f"{name}_plus")}
            cells.append(
                Cell(key=f"{mode}|{s.title}", scenario=s, policies=policies, seeds=tuple(seeds))
            )
    return cells


def _budget(result: StudyResult, stored: Mapping[str, StudyResult]) -> str:
    """Table I's columns (3x) against their bases (1x), paired per seed."""
    rows = {}
    for mode in ("paper", "drain"):
        for key, row in stored[f"table1_{mode}"].ttd.items():
            bases = result.ttd[f"{mode}|{key}"]
            rows[f"{mode}|{key}"] = {**row, **{BASE[n]: bases[n] for n in LEARNED}}
    rows, _ = with_best(rows, stored_best("table1"))
    head = ["row", "mode", "RTAW+: 3x vs 1x", "RTAW: 3x vs 1x", "RTAW+ vs RTAW at 1x",
            "RTAW+ vs RTAW at 3x", "hindsight share 1x -> 3x: RTAW / RTAW+"]  # fmt: skip
    table = []
    for key, t in rows.items():
        mode, row = key.split("|", 1)
        cells = " / ".join(f"{share(t, BASE[n])} -> {share(t, n)}" for n in LEARNED)
        pairs = [("RTAW+ 1x", "RTAW+"), ("RTAW 1x", "RTAW"), ("RTAW 1x", "RTAW+ 1x"),
                 ("RTAW", "RTAW+")]  # fmt: skip
        table.append([row, mode, *(vs(t[a], t[b]) for a, b in pairs), cells])
    r = list(rows.values())
    lines = [
        f"- RTAW+ 3x vs 1x: {pooled(r, 'RTAW+ 1x', 'RTAW+')}",
        f"- RTAW 3x vs 1x: {pooled(r, 'RTAW 1x', 'RTAW')}",
        f"- RTAW+ vs RTAW at 1x: {pooled(r, 'RTAW 1x', 'RTAW+ 1x')}",
        f"- RTAW+ vs RTAW at 3x: {pooled(r, 'RTAW', 'RTAW+')}",
    ]
    for label in (*BASE.values(), *LEARNED):
        lines.append(
            f"- {label} vs MPDM: {pooled(r, 'MPDM', label)}; vs the best rule: "
            f"{pooled(r, BEST, label)}; hindsight share {percent(pooled_share(r, label))}"
        )
    pooled_head = "Pooled over both modes (n = row-seed pairs):"
    return markdown_table(head, table) + f"\n\n{pooled_head}\n\n" + "\n".join(lines)


HORIZONS = (1, 2, 3, 4, 5, 8)
REFERENCE_HORIZON = 3  # BaselinesConfig's default: the tables' lookahead


def _horizon_cells(seeds: Sequence[int]) -> list[Cell]:
    cells = []
    for name in TABLE1:
        s = SCENARIOS[name].with_sim(episode_mode="paper")
        policies = {"MPDM": RULES["MPDM"]}
        policies.update({f"H={h}": rule("lookahead", lookahead_horizon=h) for h in HORIZONS})
        cells.append(Cell(key=s.title, scenario=s, policies=policies, seeds=tuple(seeds)))
    return cells


def _horizons(result: StudyResult, _: Mapping[str, StudyResult]) -> str:
    labels = [f"H={h}" for h in HORIZONS]
    ref = f"H={REFERENCE_HORIZON}"
    others = [h for h in labels if h != ref]
    head = ["row", "MPDM", *labels, *(f"{h} vs {ref}" for h in others)]
    table = [
        [key, *(mean_cell(t, p) for p in ("MPDM", *labels)), *(vs(t[ref], t[h]) for h in others)]
        for key, t in result.ttd.items()
    ]
    seeds = f"seeds {result.seeds[0]}-{result.seeds[-1]}"
    rows = list(result.ttd.values())
    pooled_lines = [f"- {h}: {pooled(rows, ref, h)}" for h in others]
    return (
        markdown_table(head, table)
        + f"\n\nPooled against {ref} ({seeds}, {len(rows)} rows, paper mode):\n\n"
        + "\n".join(pooled_lines)
    )


#: Every study by name.
STUDIES: dict[str, Study] = {
    s.name: s
    for s in (
        Study(name="table1_paper", description="Table I, the paper's episode mode",
              cells=_table1_cells("paper"), render=_table1_section("paper")),
        Study(name="table1_drain", description="Table I, drain mode",
              cells=_table1_cells("drain"), render=_table1_section("drain")),
        Study(name="table2", description="Table II: 500 and 1,000 robots, 5,000 tasks",
              cells=_table2_cells, render=_table2),
        Study(name="table2_hindsight", description="Table II's hindsight reference",
              cells=_table2_hindsight_cells, render=_table2_hindsight, store=False,
              default_seeds=(0, 1, 2), pairs_with=("table2",)),
        Study(name="transfer", description="Each layout's policies on every layout",
              cells=_transfer_cells, render=_transfer, store=False),
        Study(name="navigators", description="A*, SIPP and CBS execution",
              cells=_navigator_cells, render=_navigators),
        Study(name="budget_gain", description="Table I's 3x budget against its 1x bases",
              cells=_budget_cells, render=_budget, page="training.md",
              pairs_with=("table1_paper", "table1_drain")),
        Study(name="lookahead_horizon", description="lookahead's horizon, selection seeds",
              cells=_horizon_cells, render=_horizons, store=True,
              default_seeds=tuple(range(1000, 1020))),
        ANALYSIS,
        *GENERALIST_STUDIES,
    )
}  # fmt: skip


def study(name: str) -> Study:
    """The study registered as ``name``.

    Raises:
        ConfigError: Unknown name; the message lists the registered ones.
    """
    return lookup(STUDIES, "study", name)
