"""experiments/analysis.py: decision statistics on a tiny simulator and the page."""

from __future__ import annotations

import numpy as np
import pytest
from experiment_scripts import load_experiment

from rtaw_marl.policies import make_baseline
from rtaw_marl.policies.lookahead import _end_distances
from rtaw_marl.sim.builder import SimSpec

an = load_experiment("analysis", register=True)  # dataclasses look their module up

ROW = an.Row("tiny", "tiny", {"name": "open", "width": 60, "height": 60}, "astar", "-")


@pytest.fixture
def sim():
    env = {"num_robots": 3, "num_tasks": 15, "queue_len": 5, "episode_mode": "drain"}
    return SimSpec.of(env, ROW.layout, ROW.navigator, "designated").build()


def summary(sim, rule: str) -> an.Summary:
    policy = make_baseline(rule, sim.navigator, sim.layout.scale)
    decisions, ttds = an.play(sim, policy, [0])
    return an.summarise(ROW, rule, rule, decisions, ttds, mpdm_ttd=ttds[0])


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
    probe = an.Probe(sim)
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
        ours = an.end_distances(sim)
        rule = _end_distances(sim.navigator, sim.robot_xy, sim.queue_rows, mask)
        live = np.concatenate([np.arange(sim.num_robots), sim.num_robots + np.flatnonzero(mask)])
        np.testing.assert_array_equal(ours[live], rule[live])
        sim.step(int(np.flatnonzero(mask)[0]))


def test_page_has_tables_and_findings(sim) -> None:
    learned = {**summary(sim, "mpdm").__dict__, "name": "RTAW+", "policy": "RTAW+ (x)"}
    rows = [an.Summary(**learned), summary(sim, "lookahead")]
    text = an.page(rows, seeds=1, command="python experiments/analysis.py", skipped=["RTAW"])
    assert text.startswith("# ")
    assert "| tiny | RTAW+ (x) | 15 |" in text
    assert text.count("\n- **") == 6
    assert "Not loaded (skipped): RTAW." in text


def test_arguments() -> None:
    args = an.parse_args(["--checkpoint", "a.pt", "--rows", "c,Direct"])
    assert args.policies == []
    assert args.rows == ["C", "direct"]
    assert an.parse_args([]).policies == ["RTAW+", "RTAW"]
    with pytest.raises(SystemExit):
        an.parse_args(["--rows", "F"])
