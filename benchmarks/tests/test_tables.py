"""The paper's tables as studies: cells, reuse and rendering on fake TTDs (no episodes)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from benchmarks import study as study_mod
from benchmarks import tables
from benchmarks.generalist import HOLDOUT_ROW
from benchmarks.studies import STUDIES, TABLE1
from benchmarks.study import StudyResult, load_result, run_study
from benchmarks.tables import BEST, DATA, ORDER, TABLE2, section, stored_best, with_best
from rtaw_marl.scenarios import SCENARIOS

pytestmark = pytest.mark.unit

#: Mean TTD per policy of the fake evaluations (lower is better).
MEANS = {"MPDM": 1000, "RBTS": 990, "lookahead": 920, "hungarian": 1010, "hindsight": 850,
         "RTAW": 970, "RTAW+": 880}  # fmt: skip


def fake_ttd(labels, n: int) -> dict[str, list[float]]:
    """Per-seed TTDs around ``MEANS`` (exactly, for an even number of seeds)."""
    noise = 30.0 * (-1.0) ** np.arange(n)  # common to all policies: paired
    return {p: list(MEANS.get(p, 900) + noise) for p in labels}


@pytest.fixture
def fake(monkeypatch):
    """No episodes: each cell "evaluates" to fake TTDs; records what was asked."""
    calls: list[tuple[str, tuple[str, ...], str]] = []

    def run_cell(job):
        cell, todo, _, _ = job
        calls.append((cell.key, tuple(todo), str(cell.scenario.spec().sim.episode_mode)))
        ttd = fake_ttd(todo, len(cell.seeds))
        return cell.key, ttd, dict.fromkeys(ttd, 0.1)

    monkeypatch.setattr(study_mod, "_run_cell", run_cell)
    monkeypatch.setattr(study_mod.PolicyRef, "loads", lambda self: None)
    return calls


def test_section_has_both_tables_and_pooled_lines():
    rows = {f"row {i}": fake_ttd(MEANS, 4) for i in range(3)}
    means, comparisons, summary = section(rows).split("\n\n")
    assert means.splitlines()[0].startswith("| setting | MPDM | RBTS | lookahead | hungarian")
    assert "| RTAW | RTAW+ | hindsight share: lookahead / RTAW / RTAW+ |" in means
    assert "RTAW+ vs lookahead" in comparisons
    # No stored best rule given: no column, no pooled line (not a column of dashes).
    assert "best rule" not in comparisons
    assert "the best rule" not in summary
    assert "- RTAW+ vs MPDM, pooled: +12.0% [" in summary
    assert "- RTAW+ beats lookahead on 3 of 3 rows (significantly on 3;" in summary
    assert "- hindsight share, pooled (lookahead / RTAW / RTAW+): 53% / 20% / 80%" in summary
    assert ">= +10% vs MPDM pooled: met (+12.0%); >= 70% hindsight share pooled: met (80%)" in (
        summary
    )


def test_missing_policies_show_a_dash():
    text = section({"r": fake_ttd(["MPDM", "RBTS", "lookahead", "hungarian", "RTAW"], 2)})
    assert "| r | 1000 | 990 | 920 | 1010 | - | 970 | - | - / - / - |" in text
    assert "| r | - | - | - | - | +3.0% [+3.0, +3.0]* |" in text
    assert "- RTAW+ vs MPDM, pooled: -" in text
    assert "RTAW+ beats MPDM on 0 of 0 rows" in text


def test_rows_are_compared_with_the_stored_best_rule_of_their_setting():
    rows = {"a": fake_ttd(MEANS, 4), "b": fake_ttd(MEANS, 4)}
    chosen = list(np.array(rows["a"]["hungarian"]))  # the same episodes as the row's
    marked, names = with_best(rows, {"a": ("hungarian", chosen)})
    assert names == {"a": "hungarian"}
    assert marked["a"][BEST] == chosen
    assert BEST not in marked["b"]
    _, comparisons, summary = section(marked, names).split("\n\n")
    assert "| setting | best rule (seeds 1000-1019) | RTAW+ vs MPDM" in comparisons
    # RTAW (970) against hungarian (1010): +4.0%, not against the row's best mean (920).
    assert "| a | hungarian | +12.0%" in comparisons
    assert "+4.0% [+4.0, +4.0]* |" in comparisons
    assert "| b | - |" in comparisons
    assert "- RTAW vs the best rule, pooled: +4.0% [" in summary


def test_a_stored_best_rule_from_other_episodes_is_an_error():
    rows = {"a": fake_ttd(MEANS, 4)}
    with pytest.raises(ValueError, match="a: the stored lookahead TTDs differ"):
        with_best(rows, {"a": ("lookahead", [1.0, 2.0, 3.0, 4.0])})


def test_stored_best_reads_the_search_tables_choices(tmp_path):
    row = {"best_rule": {"name": "mpdm"}, "ttd": {"mpdm": [3, 4], "lookahead": [1, 2]}}
    (tmp_path / "search_x.json").write_text(json.dumps({"rows": {"k": row}}))
    assert stored_best("x", data=tmp_path) == {"k": ("MPDM", [3.0, 4.0])}


def test_every_stored_table_row_has_its_best_rule():
    """The older tables' rows all find their bar in the stored search tables."""
    best = stored_best("table1", "table2", "holdout", "unseen")
    for mode in ("paper", "drain"):
        assert all(f"{mode}|{SCENARIOS[n].title}" in best for n in TABLE1)
    assert all(SCENARIOS[n].title in best for n in TABLE2)
    unseen = load_result(DATA / "generalist_unseen.json")
    assert all(HOLDOUT_ROW.get(k, k) in best for k in unseen.ttd)


def test_table1_is_every_row_at_both_robot_counts_with_its_long_policies(fake, tmp_path):
    result = run_study(STUDIES["table1_paper"], [0, 1], tmp_path)
    assert list(result.ttd) == [SCENARIOS[n].title for n in TABLE1]
    assert len(fake) == 12
    assert {mode for *_, mode in fake} == {"paper"}
    assert all(labels == ORDER for _, labels, _ in fake)
    cells = STUDIES["table1_drain"].cells([0])
    assert {c.scenario.spec().sim.episode_mode for c in cells} == {"drain"}
    learned = {ref.name for c in cells for k, ref in c.policies.items() if k.startswith("RTAW")}
    assert len(learned) == 24
    assert all(name.endswith(("_long", "_long_plus")) for name in learned)


def test_reuse_evaluates_only_the_learned_columns(fake, tmp_path):
    rules = fake_ttd(["MPDM", "RBTS", "lookahead", "hungarian", "hindsight"], 2)
    stale = {**rules, "RTAW": [1.0, 2.0]}  # a learned column is never reused
    stored = StudyResult(seeds=[0, 1], ttd={SCENARIOS[n].title: stale for n in TABLE1})
    result = run_study(STUDIES["table1_paper"], [0, 1], tmp_path, reuse=stored)
    assert {labels for _, labels, _ in fake} == {("RTAW", "RTAW+")}
    row = result.ttd["A* layout C, M=100"]
    assert list(row) == list(ORDER)
    assert row["MPDM"] == rules["MPDM"]
    assert row["RTAW"] != [1.0, 2.0]


def test_transfer_has_a_table_per_learned_policy(fake, tmp_path):
    s = STUDIES["transfer"]
    text = s.render(run_study(s, [0, 1], tmp_path), {})
    assert "| RTAW: trained on \\ evaluated on | A |" in text
    assert "| RTAW+: trained on \\ evaluated on | A |" in text
    assert "- RTAW+ vs MPDM, pooled: own layout +12.0%" in text
    assert ("C on D", ("RTAW", "RTAW+"), "drain") in fake


def test_navigators_run_each_execution_without_noise(tmp_path):
    cells = STUDIES["navigators"].cells([0])
    assert len(cells) == 15
    for c in cells:
        sim = c.scenario.spec().sim
        assert (sim.num_tasks, sim.noise_mean, sim.noise_var) == (50, 0.0, 0.0)
        assert c.policies["RTAW+"].name.endswith("_astar_m10_plus")


def test_budget_gain_pairs_each_row_with_its_bases(fake, tmp_path, monkeypatch):
    s = STUDIES["budget_gain"]
    result = run_study(s, list(range(20)), tmp_path)
    asked = {labels for _, labels, _ in fake}
    assert asked == {("RTAW", "RTAW+")}
    cells = s.cells([0])
    assert {c.policies["RTAW"].name for c in cells} >= {"C_astar_m100"}
    table1 = fake_ttd(MEANS, 20)
    table1["RTAW+"] = [t - 20 for t in table1["RTAW+"]]  # 3x: 860 against its base's 880
    rows = {SCENARIOS[n].title: table1 for n in TABLE1}
    stored = {
        f"table1_{m}": StudyResult(seeds=list(range(20)), ttd=rows) for m in ("paper", "drain")
    }
    best = {"best_rule": {"name": "lookahead"}, "ttd": {"lookahead": table1["lookahead"]}}
    search = {"rows": {f"{m}|{k}": best for k in rows for m in ("paper", "drain")}}
    (tmp_path / "search_table1.json").write_text(json.dumps(search))
    monkeypatch.setattr(tables, "DATA", tmp_path)
    text = s.render(result, stored)
    assert text.count("| A* layout C, M=100 |") == 2  # paper and drain
    assert "- RTAW+ 3x vs 1x: +2.3% [+2.3, +2.3]* (n=480)" in text
    assert "- RTAW 3x vs 1x: +0.0%" in text
    # 860 against lookahead's 920 (the fake "best rule" of every row).
    assert "- RTAW+ vs MPDM: +14.0% [+14.0, +14.0]* (n=480); vs the best rule: +6.5%" in text


def test_the_horizon_check_runs_on_selection_seeds_and_h0_is_mpdm(tmp_path):
    s = STUDIES["lookahead_horizon"]
    assert min(s.default_seeds) >= 1000
    assert len(s.default_seeds) >= 20
    from benchmarks.study import Cell, Study, rule

    tiny = SCENARIOS["C_astar_m10"].with_sim(num_robots=5, num_tasks=40, episode_mode="paper")
    policies = {"MPDM": rule("mpdm"), "H=0": rule("lookahead", lookahead_horizon=0),
                "H=3": rule("lookahead")}  # fmt: skip

    def cells(seeds):
        return [Cell(key="t", scenario=tiny, policies=policies, seeds=tuple(seeds))]

    probe = Study(name="h", description="h", render=lambda r, _: "", cells=cells)
    ttd = run_study(probe, [1000, 1001], tmp_path).ttd["t"]
    assert ttd["H=0"] == ttd["MPDM"]
    assert ttd["H=3"] != ttd["MPDM"]


def test_stored_results_of_the_docs_are_studies_of_the_same_cells():
    """benchmarks/data holds, for each stored study, exactly its cells and policies."""
    data = Path(__file__).resolve().parents[1] / "data"
    for name in ("table1_paper", "table1_drain", "table2", "navigators", "budget_gain"):
        stored = load_result(data / f"{name}.json")
        assert stored is not None, name
        cells = STUDIES[name].cells(stored.seeds)
        assert list(stored.ttd) == [c.key for c in cells], name
        for c in cells:
            assert set(stored.ttd[c.key]) <= set(c.policies), (name, c.key)
        assert json.loads((data / f"{name}.json").read_text())["seeds"] == list(range(20))
