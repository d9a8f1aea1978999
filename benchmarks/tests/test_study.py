"""Studies: cells run through the journal, resume, reuse stored rules, render, rewrite docs."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import pytest

from benchmarks import tables
from benchmarks.studies import STUDIES, study
from benchmarks.study import (
    Cell,
    Study,
    StudyResult,
    checkpoint,
    learned,
    load_result,
    replace_section,
    rule,
    run_study,
    save_result,
)
from rtaw_marl.errors import ConfigError
from rtaw_marl.evaluation import evaluate
from rtaw_marl.policies import make_baseline
from rtaw_marl.scenarios import SCENARIOS
from rtaw_marl.sim.builder import build_sim

pytestmark = pytest.mark.integration

SMALL = SCENARIOS["C_astar_m10"].with_sim(num_tasks=30)


def _study(policies: dict | None = None) -> Study:
    policies = policies or {"MPDM": rule("mpdm"), "lookahead": rule("lookahead")}
    return Study(
        name="small",
        description="a small test study",
        cells=lambda seeds: [
            Cell(key="C, M=10", scenario=SMALL, policies=policies, seeds=tuple(seeds))
        ],
        render=lambda result, _: json.dumps(result.ttd),
    )


def test_a_study_runs_what_evaluate_runs(tmp_path: Path) -> None:
    result = run_study(_study(), [0, 1], tmp_path)
    sim = build_sim(SMALL.spec())
    direct = evaluate(sim, {"MPDM": make_baseline("mpdm")}, [0, 1])
    assert result.ttd["C, M=10"]["MPDM"] == direct["MPDM"]["ttd"]
    assert list(result.ttd["C, M=10"]) == ["MPDM", "lookahead"]
    assert (tmp_path / "C_M_10.episodes.jsonl").is_file()


def test_resume_replays_the_journal(tmp_path: Path) -> None:
    first = run_study(_study(), [0, 1], tmp_path)
    journal = tmp_path / "C_M_10.episodes.jsonl"
    lines = journal.read_text().splitlines()
    # Fake a recorded episode: a resumed study takes it instead of running it.
    entry = json.loads(lines[1])
    entry["metrics"]["ttd"] = 1.0
    journal.write_text("\n".join([lines[0], json.dumps(entry), *lines[2:]]) + "\n")
    resumed = run_study(_study(), [0, 1], tmp_path, resume=True)
    label, seed = entry["policy"], entry["seed"]
    assert resumed.ttd["C, M=10"][label][[0, 1].index(seed)] == 1.0
    fresh = run_study(_study(), [0, 1], tmp_path, resume=False)
    assert fresh.ttd == first.ttd


def test_reuse_takes_rules_only_and_only_with_the_same_seeds(tmp_path: Path) -> None:
    stored = StudyResult(
        seeds=[0, 1], ttd={"C, M=10": {"MPDM": [1.0, 2.0], "lookahead": [3.0, 4.0]}}
    )
    reused = run_study(_study(), [0, 1], tmp_path, reuse=stored)
    assert reused.ttd["C, M=10"] == stored.ttd["C, M=10"]
    other_seeds = run_study(_study(), [0, 2], tmp_path, reuse=stored)
    assert other_seeds.ttd["C, M=10"]["MPDM"] != [1.0, 2.0]


def test_a_learned_policy_is_never_reused(tmp_path: Path) -> None:
    policies = {"MPDM": rule("mpdm"), "RTAW+": learned("C_astar_m10_long_plus")}
    stored = StudyResult(seeds=[0], ttd={"C, M=10": {"MPDM": [1.0], "RTAW+": [2.0]}})
    result = run_study(_study(policies), [0], tmp_path, reuse=stored)
    assert result.ttd["C, M=10"]["MPDM"] == [1.0]
    assert result.ttd["C, M=10"]["RTAW+"] != [2.0]


def test_a_missing_learned_policy_is_skipped_with_a_warning(tmp_path: Path, capsys) -> None:
    policies = {"MPDM": rule("mpdm"), "RTAW": learned("no_such_policy")}
    result = run_study(_study(policies), [0], tmp_path)
    assert list(result.ttd["C, M=10"]) == ["MPDM"]
    assert "RTAW (no_such_policy) skipped" in capsys.readouterr().err


def test_rule_parameters_are_checked_up_front() -> None:
    with pytest.raises(ConfigError, match="unknown rule"):
        rule("nearest")
    with pytest.raises(ConfigError, match="lookahead_horizon"):
        rule("lookahead", lookahead_horizon=-1)


def test_results_round_trip_and_sections_are_replaced(tmp_path: Path) -> None:
    result = StudyResult(seeds=[0, 1], ttd={"row": {"MPDM": [1.0, 2.0]}})
    save_result(tmp_path / "data" / "x.json", result)
    assert load_result(tmp_path / "data" / "x.json") == result
    page = tmp_path / "page.md"
    page.write_text("head\n<!-- BEGIN x -->\nold\n<!-- END x -->\ntail\n")
    replace_section(page, "x", "new body")
    text = page.read_text()
    assert text.startswith("head\n<!-- BEGIN x -->\n_Generated ")
    assert "new body\n<!-- END x -->\ntail\n" in text
    assert "old" not in text
    with pytest.raises(ConfigError, match="no <!-- BEGIN y -->"):
        replace_section(page, "y", "body")


def test_every_study_renders_from_its_own_cells(tmp_path: Path, monkeypatch) -> None:
    """Each registered study's cells and renderer agree (fake TTDs, no episodes; no
    stored best rule matches fake episodes, so none is stored)."""
    for part in ("table1", "table2", "holdout", "unseen"):
        (tmp_path / f"search_{part}.json").write_text('{"rows": {}}')
    monkeypatch.setattr(tables, "DATA", tmp_path)
    for name, s in STUDIES.items():
        seeds = list(s.default_seeds[:3])
        ttd = {
            c.key: {k: [100.0 + i + j for j in range(len(seeds))] for i, k in enumerate(c.policies)}
            for c in s.cells(seeds)
        }
        result = StudyResult(seeds=seeds, ttd=ttd)
        stored = {}
        for other in s.pairs_with:
            cells = STUDIES[other].cells(seeds)
            stored[other] = StudyResult(
                seeds=seeds,
                ttd={c.key: {k: [110.0, 111.0, 112.0] for k in c.policies} for c in cells},
            )
        text = s.render(result, stored)
        assert "|---|" in text, name


def test_only_the_horizon_check_uses_selection_seeds() -> None:
    for name, s in STUDIES.items():
        if name == "lookahead_horizon":
            assert min(s.default_seeds) >= 1000
        else:
            assert max(s.default_seeds) < 20


def test_unknown_study_lists_them() -> None:
    with pytest.raises(ConfigError, match=r"unknown study 'table3'.*table1_paper"):
        study("table3")


def test_a_checkpoint_file_is_a_learned_policy(tmp_path: Path) -> None:
    from rtaw_marl.policies.pretrained.registry import pretrained_path

    path = pretrained_path("C_astar_m10_long_plus")
    by_file = run_study(_study({"RTAW+": checkpoint(path)}), [0], tmp_path / "a")
    by_name = run_study(_study({"RTAW+": learned("C_astar_m10_long_plus")}), [0], tmp_path / "b")
    assert by_file.ttd == by_name.ttd


def test_a_checkpoint_replaced_at_the_same_path_is_not_replayed(tmp_path: Path) -> None:
    """The cell's journal keys the checkpoint's episodes by its contents: replaced, a
    resumed study runs them again (as a fresh study does); the rule's are replayed."""
    import shutil

    from rtaw_marl.policies.pretrained.registry import pretrained_path

    ckpt = tmp_path / "policy.pt"
    shutil.copy(pretrained_path("C_astar_m10_long_plus"), ckpt)
    policies = {"MPDM": rule("mpdm"), "RTAW+": checkpoint(ckpt)}
    first = run_study(_study(policies), [0, 1], tmp_path / "run")
    shutil.copy(pretrained_path("C_astar_m10_long"), ckpt)
    resumed = run_study(_study(policies), [0, 1], tmp_path / "run", resume=True)
    fresh = run_study(_study(policies), [0, 1], tmp_path / "fresh")
    assert resumed.ttd == fresh.ttd
    assert resumed.ttd["C, M=10"]["RTAW+"] != first.ttd["C, M=10"]["RTAW+"]
    assert resumed.ttd["C, M=10"]["MPDM"] == first.ttd["C, M=10"]["MPDM"]
    entries = (tmp_path / "run" / "C_M_10.episodes.jsonl").read_text().splitlines()[1:]
    assert len(entries) == 4 + 2  # both labels on two seeds, then RTAW+ again


def test_a_study_refuses_a_repeated_seed(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match=r"^seeds lists a seed more than once: 0 \(2 times\)"):
        run_study(_study(), [0, 1, 0], tmp_path)


def test_reuse_learned_takes_every_stored_label_and_runs_the_missing_ones(tmp_path: Path) -> None:
    policies = {"MPDM": rule("mpdm"), "lookahead": rule("lookahead"),
                "RTAW+": learned("C_astar_m10_long_plus")}  # fmt: skip
    stored = StudyResult(seeds=[0], ttd={"C, M=10": {"MPDM": [1.0], "RTAW+": [2.0]}})
    result = run_study(_study(policies), [0], tmp_path, reuse=stored, reuse_learned=True)
    row = result.ttd["C, M=10"]
    assert (row["MPDM"], row["RTAW+"]) == ([1.0], [2.0])
    assert row["lookahead"] != [1.0]  # missing from the stored result: evaluated


def test_table1_experiment_is_the_study_of_table_one() -> None:
    """Each job of ``rtaw-eval -m experiment=table1`` evaluates the setting, seeds and
    shipped policies of that row of the table1_paper study (the sweep is the same
    evaluation on a cluster)."""
    from rtaw_marl.config import compose, to_typed
    from rtaw_marl.scenarios import ROWS, SCENARIOS

    cells = {c.key: c for c in STUDIES["table1_paper"].cells(list(range(20)))}
    for row, name in ROWS.items():
        cfg = compose(config_name="eval", overrides=["experiment=table1", f"row={row}"])
        cell = cells[SCENARIOS[name].title]
        assert to_typed(cfg).sim_spec() == cell.scenario.spec()
        assert list(cfg.seeds) == list(cell.seeds)
        learned = [ref.name for label, ref in cell.policies.items() if ref.kind == "pretrained"]
        assert sorted(cfg.pretrained) == sorted(learned)


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["table3"], "unknown study 'table3'"),
        (["transfer", "--seeds", "2", "2"], "--seeds lists a seed more than once: 2 (2 times)"),
        (["transfer", "--seeds", "-1"], "--seeds[0] must be an integer >= 0"),
        (["transfer", "--workers", "0"], "--workers must be at least 1, got 0"),
        (["transfer", "--reuse-learned"], "--reuse-learned needs --reuse"),
    ],
)
def test_the_runner_refuses_bad_arguments(
    argv: list[str], message: str, capsys: pytest.CaptureFixture[str]
) -> None:
    """``python -m benchmarks.run`` checks its arguments before any work: exit 2, one line."""
    from benchmarks.run import parse

    with pytest.raises(SystemExit) as exit_info:
        parse(argv)
    assert exit_info.value.code == 2
    err = capsys.readouterr().err
    assert message in err
    assert "Traceback" not in err


def test_the_runner_runs_a_study_and_writes_its_page(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """``--write`` stores the result in ``--data`` and rewrites only the study's section."""
    import benchmarks.run as runner
    from benchmarks.studies import STUDIES as REGISTRY

    monkeypatch.setitem(REGISTRY, "tiny", dataclasses.replace(_study(), name="tiny"))
    docs, data = tmp_path / "docs", tmp_path / "data"
    docs.mkdir()
    page = "before\n<!-- BEGIN tiny -->\nold\n<!-- END tiny -->\nafter\n"
    (docs / "results.md").write_text(page)
    argv = ["tiny", "--seeds", "0", "1", "--output", str(tmp_path / "run")]
    runner.main([*argv, "--docs", str(docs), "--data", str(data), "--write"])
    text = (docs / "results.md").read_text()
    assert text.startswith("before\n<!-- BEGIN tiny -->\n")
    assert text.endswith("<!-- END tiny -->\nafter\n")
    assert "old" not in text
    stored = load_result(data / "tiny.json")
    assert stored is not None
    assert stored.seeds == [0, 1]
    assert not list((tmp_path / "run").glob(".*.lock"))
    printed = capsys.readouterr().out
    assert "results:" in printed
    # The printed tables are kept beside the study's result: <study>.txt.
    assert (tmp_path / "run" / "tiny.txt").read_text() == printed
