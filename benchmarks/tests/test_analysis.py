"""evaluation.analysis: decision statistics on a tiny simulator, the study and its page."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from benchmarks.analysis import Probe, Summary, play, render, section, summarise
from benchmarks.analysis.decisions import end_distances
from benchmarks.analysis.study import DEFAULT_ROWS, analysis_study, run
from benchmarks.studies import STUDIES
from benchmarks.study import Cell, checkpoint, replace_section, rule
from rtaw_marl.errors import ConfigError
from rtaw_marl.evaluation import evaluate
from rtaw_marl.policies import make_baseline
from rtaw_marl.policies.lookahead import rollout_distances
from rtaw_marl.scenarios import EVAL_SEEDS, SCENARIOS
from rtaw_marl.sim.builder import build_sim

pytestmark = pytest.mark.unit

ROOT = Path(__file__).resolve().parents[2]
TINY = SCENARIOS["C_astar_m10"].with_sim(
    num_robots=3, num_tasks=15, queue_len=5, episode_mode="drain"
)


@pytest.fixture
def sim():
    return build_sim(TINY.spec())


def summary(sim, rule_name: str) -> Summary:
    policy = make_baseline(rule_name)
    decisions, ttds = play(sim, policy, [0])
    return summarise(
        decisions, ttds, ttds[0], row="tiny", short="tiny", name=rule_name, policy=rule_name
    )


def test_mpdm_never_deviates_from_the_nearest_task(sim) -> None:
    s = summary(sim, "mpdm")
    assert s.decisions == 15
    assert s.nearest == 1.0
    assert s.deviations == 0
    assert s.extra_mean is None
    assert s.chosen_free is None


def test_lookahead_always_agrees_with_itself(sim) -> None:
    s = summary(sim, "lookahead")
    assert s.lookahead == 1.0
    assert s.deviations == s.lookahead_deviations > 0
    assert s.agree_if_lookahead_deviates == 1.0
    assert s.nearest_if_lookahead_deviates == 0.0
    assert s.extra_mean > 0


def test_probing_the_rules_leaves_the_simulator_unchanged(sim) -> None:
    """Asking MPDM and lookahead about a state reads it only."""
    sim.reset(0)
    probe = Probe(sim)
    for _ in range(5):
        before = sim.state()
        probe.classify(sim, int(np.flatnonzero(sim.queue_mask)[-1]))
        after = sim.state()
        assert before.scalars == after.scalars
        for key, value in before.arrays.items():
            np.testing.assert_array_equal(value, after.arrays[key])
        sim.step(int(np.flatnonzero(sim.queue_mask)[-1]))


def test_end_distances_match_the_rule(sim) -> None:
    """The rollout inputs rebuilt from the simulator equal the rule's own, where read."""
    sim.reset(0)
    for _ in range(5):
        mask = sim.queue_mask
        ours = end_distances(sim)
        rule_ends = rollout_distances(sim.distance_model, sim.robot_xy, sim.queue_rows, mask)
        live = np.concatenate([np.arange(sim.num_robots), sim.num_robots + np.flatnonzero(mask)])
        np.testing.assert_array_equal(ours[live], rule_ends[live])
        sim.step(int(np.flatnonzero(mask)[0]))


def test_section_has_tables_and_findings(sim) -> None:
    learned = dataclasses.replace(summary(sim, "mpdm"), name="RTAW+", policy="RTAW+ (x)")
    rows = [learned, summary(sim, "lookahead")]
    text = section(
        rows, [0], horizon=3, command="python -m benchmarks.run analysis", skipped=["RTAW"]
    )
    assert text.startswith("Rows: tiny; seed 0; `lookahead` with H = 3.")
    assert "| tiny | RTAW+ (x) | 15 |" in text
    assert text.count("\n- **") == 6
    assert "Not loaded (skipped): RTAW." in text


def test_run_plays_every_policy_and_skips_what_does_not_load(tmp_path: Path) -> None:
    policies = {"MPDM": rule("mpdm"), "gone.pt": checkpoint(tmp_path / "gone.pt"),
                "lookahead": rule("lookahead")}  # fmt: skip
    cell = Cell(key="tiny", scenario=TINY, policies=policies, seeds=(0, 1))
    result = run([cell], tmp_path)
    plain = evaluate(build_sim(TINY.spec()), {"MPDM": make_baseline("mpdm")}, [0, 1])
    assert result.ttd["tiny"]["MPDM"] == plain["MPDM"]["ttd"]
    assert list(result.ttd["tiny"]) == ["MPDM", "lookahead"]
    assert result.extra["skipped"] == ["gone.pt on tiny"]
    (s,) = result.extra["summaries"]
    assert (s["name"], s["decisions"], s["seeds"]) == ("lookahead", 30, 2)
    assert s["mpdm_ttd"] == pytest.approx(np.mean(plain["MPDM"]["ttd"]))
    text = render(result)
    assert "| tiny | lookahead | 30 |" in text
    assert "Not loaded (skipped):" in text


def test_the_study_reads_its_rows_from_the_scenarios() -> None:
    study = STUDIES["analysis"]
    assert (study.page, study.store, study.default_seeds) == ("analysis.md", False, EVAL_SEEDS)
    cells = study.cells([0, 1])
    assert [c.key for c in cells] == ["A* layout C", "Direct (open 60x60)"]
    c = cells[0]
    assert c.scenario == SCENARIOS["C_astar_m10"].with_sim(episode_mode="drain")
    assert list(c.policies) == ["MPDM", "RTAW+", "RTAW", "lookahead"]
    assert c.policies["RTAW+"].name == "C_astar_m10_long_plus"
    assert c.seeds == (0, 1)


def test_policies_and_checkpoints_from_python() -> None:
    (cell,) = analysis_study(rows=["B"], checkpoints=["a.pt"]).cells([0])
    assert list(cell.policies) == ["MPDM", "a.pt", "lookahead"]
    (cell,) = analysis_study(rows=["A_m100"], policies=["C_astar_m10_plus"]).cells([0])
    assert cell.key == "A* layout A, M=100"
    assert cell.policies["C_astar_m10_plus"].name == "C_astar_m10_plus"
    assert DEFAULT_ROWS == ("C", "direct")
    with pytest.raises(ConfigError, match="available"):
        analysis_study(rows=["F"])
    with pytest.raises(ConfigError):
        analysis_study(policies=[])


def test_the_page_has_the_section_the_study_rewrites(tmp_path: Path) -> None:
    page = tmp_path / "analysis.md"
    page.write_text((ROOT / "docs" / "analysis.md").read_text())
    replace_section(page, "analysis", "NEW")
    text = page.read_text()
    assert "NEW\n<!-- END analysis -->" in text
    assert text.startswith("# What the learned policies do differently")
    assert "## Choices" not in text  # the tables are generated
