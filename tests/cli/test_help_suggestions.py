""" "Did you mean": a misspelt key, group option or registry name is one ``error:`` line
(exit status 2, no traceback) that lists the valid names and suggests the closest."""

from __future__ import annotations

import pytest

from rtaw_marl.errors import ConfigError, close_names, did_you_mean, lookup, unknown_name
from rtaw_marl.policies import make_baseline
from rtaw_marl.scenarios.registry import scenario
from rtaw_marl.sim.options import navigator_option

pytestmark = pytest.mark.integration


@pytest.mark.parametrize(
    ("args", "listing", "suggestion"),
    [
        (["sim.num_robot=5"], "valid keys there: num_robots, num_tasks", "'sim.num_robots'"),
        (["+layout.widht=3"], "valid keys there: path, width, height", "'layout.width'"),
        (["navigatr=sipp"], "valid keys there: sim, layout, navigator", "'navigator'"),
        (["navigator=sipq"], "available: astar, cbs, direct, pibt, sipp", "'navigator=sipp'"),
        (["row=c"], "available: A, A_m100, B", "'row=C'"),
        (["hydra/launcher=jobilb"], "available: basic, joblib", "'hydra/launcher=joblib'"),
        (["policy=[mpdm,lookahed]"], "available: batch, checkpoint, hindsight", "'lookahead'"),
    ],
)
def test_eval_suggests_the_closest_name(
    args: list[str], listing: str, suggestion: str, cli
) -> None:
    result = cli("eval", "scenario=poc", "progress=false", *args)
    assert result.code == 2
    errors = [line for line in result.err.splitlines() if line.startswith("error:")]
    assert errors == [result.err.strip().splitlines()[-1]]
    assert listing in errors[0]
    assert errors[0].endswith(f"; did you mean {suggestion}?")
    assert "Traceback" not in result.err + result.out


def test_train_suggests_a_key_of_the_chosen_option(cli) -> None:
    result = cli("train", "model=rtaw_plus", "model.embed_dmi=8")
    assert result.code == 2
    assert result.err.strip().endswith("did you mean 'model.embed_dim'?")


def test_nothing_close_adds_no_suggestion(cli) -> None:
    result = cli("eval", "navigator=dijkstra")
    assert result.code == 2
    assert result.err.strip() == (
        "error: Could not find 'navigator/dijkstra'; available: astar, cbs, direct, pibt, sipp"
    )


def test_registries_share_the_suggestion() -> None:
    """Python API lookups: the same helper, the same message shape."""
    with pytest.raises(ConfigError, match=r"; did you mean 'lookahead'\?$"):
        make_baseline("lookahed")
    with pytest.raises(ConfigError, match=r"unknown scenario 'pco'; .*did you mean 'poc'\?$"):
        scenario("pco")
    with pytest.raises(ConfigError, match=r"did you mean 'sipp'\?$"):
        navigator_option("sipq")
    with pytest.raises(ConfigError, match=r"did you mean 'navigator\.cache_mb'\?$"):
        navigator_option({"name": "astar", "cache_md": 1})


@pytest.mark.parametrize(
    ("name", "choices", "close"),
    [
        ("lookahed", ["mpdm", "lookahead", "rbts"], ["lookahead"]),
        ("c", ["A", "B", "C", "C_m100"], ["C"]),  # case first, before near spellings
        ("rbst", ["mpdm", "rbts", "random"], ["rbts"]),
        ("dijkstra", ["astar", "cbs", "direct", "pibt", "sipp"], []),
    ],
)
def test_close_names(name: str, choices: list[str], close: list[str]) -> None:
    assert close_names(name, choices) == close


def test_did_you_mean_spells_what_to_type() -> None:
    assert did_you_mean("sipq", ["sipp", "astar"], prefix="navigator=") == (
        "; did you mean 'navigator=sipp'?"
    )
    assert did_you_mean("num_robot", ["num_robots", "num_tasks"]) == (
        "; did you mean 'num_robots'?"
    )
    assert did_you_mean("ab", ["abc", "abd"]) == "; did you mean 'abc' or 'abd'?"
    assert did_you_mean("zzz", ["abc"]) == ""
    error = unknown_name("policy", "mdpm", ["rbts", "mpdm"])
    assert str(error) == "unknown policy 'mdpm'; available: mpdm, rbts; did you mean 'mpdm'?"
    with pytest.raises(ConfigError, match="did you mean 'b'"):
        lookup({"a": 1, "b": 2}, "thing", "B")
