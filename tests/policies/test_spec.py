"""PolicySpec: the one resolver from a label's meaning to a policy."""

from __future__ import annotations

import pickle
import sys
from pathlib import Path

import pytest

from rtaw_marl.errors import ConfigError
from rtaw_marl.evaluation import evaluate
from rtaw_marl.policies import BaselinesConfig, Lookahead
from rtaw_marl.policies.pretrained.registry import pretrained_path
from rtaw_marl.policies.spec import PolicySpec
from rtaw_marl.scenarios import SCENARIOS
from rtaw_marl.sim.builder import build_sim

pytestmark = pytest.mark.unit


def test_a_rule_spec_carries_its_parameters_and_pickles() -> None:
    spec = PolicySpec.rule("lookahead", {"lookahead_horizon": 2})
    assert spec == pickle.loads(pickle.dumps(spec))
    policy = spec.build()
    assert isinstance(policy, Lookahead)
    assert policy.horizon == 2
    assert spec.path() is None
    assert spec.loads() is None
    assert PolicySpec.rule("mpdm", BaselinesConfig()).params == PolicySpec.rule("mpdm").params


@pytest.mark.parametrize(
    ("make", "message"),
    [
        (lambda: PolicySpec.rule("mpmd"), "unknown rule 'mpmd'"),
        (lambda: PolicySpec.rule("lookahead", {"horizon": 2}), "horizon"),
        (lambda: PolicySpec("network", "x"), "unknown policy kind 'network'"),
    ],
)
def test_bad_specs_fail_when_made(make, message: str) -> None:
    with pytest.raises((ConfigError, TypeError), match=message):
        make()


def test_learned_specs_name_their_files(tmp_path: Path) -> None:
    shipped = PolicySpec("pretrained", "A_astar_m10")
    assert shipped.path() == pretrained_path("A_astar_m10")
    # A checkpoint= value is a file, or else a shipped name.
    assert PolicySpec("checkpoint", "A_astar_m10").path() == pretrained_path("A_astar_m10")
    missing = PolicySpec("checkpoint", str(tmp_path / "nope.pt"))
    why = missing.loads()
    assert why is not None
    assert "nope" in why


def test_an_import_spec_plays_like_the_rule_it_wraps(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    (tmp_path / "spec_rules.py").write_text(
        "from rtaw_marl.policies import MPDM\n\nclass Mine(MPDM):\n    name = 'mine'\n"
    )
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.delitem(sys.modules, "spec_rules", raising=False)
    sim = build_sim(SCENARIOS["C_astar_m10"].with_sim(num_tasks=20).spec())
    mine = PolicySpec("import", "spec_rules:Mine").build(sim)
    mpdm = PolicySpec.rule("mpdm").build(sim)
    ttd = evaluate(sim, {"mine": mine, "mpdm": mpdm}, [0, 1])
    assert ttd["mine"]["ttd"] == ttd["mpdm"]["ttd"]
