"""Scenario mixes: the member syntax, its errors, and what the generalist's mix holds out."""

from __future__ import annotations

import dataclasses

import pytest

from rtaw_marl.config import compose, to_typed
from rtaw_marl.errors import ConfigError
from rtaw_marl.scenarios import SCENARIOS
from rtaw_marl.scenarios.mix import GENERALIST, _resized, member_spec, mix_specs
from rtaw_marl.sim.builder import build_sim

pytestmark = pytest.mark.unit


def test_member_keys_change_the_scenario() -> None:
    base = SCENARIOS["C_astar_m10"].spec()
    spec = member_spec("C_astar_m10:m30:n5:t40:paper")
    assert (spec.sim.num_robots, spec.sim.queue_len, spec.sim.num_tasks) == (30, 5, 40)
    assert spec.sim.episode_mode == "paper"
    assert (spec.layout, spec.navigator, spec.tasks) == (base.layout, base.navigator, base.tasks)
    assert member_spec("C_astar_m10") == base


@pytest.mark.parametrize(
    ("member", "message"),
    [
        ("C_astar_m7", "unknown scenario 'C_astar_m7'"),
        ("C_astar_m10:x3", "'x3' is not m<robots>, n<queue slots>, t<tasks>, s<layout size>"),
        ("C_astar_m10:s", "'s' is not m<robots>"),
        ("C_astar_m10:Random", "'Random' is not m<robots>"),
        ("C_astar_m10:s2", r"'C_astar_m10:s2': no 4x2 shelf fits in 2x2"),
        ("C_astar_m10:s0", "layout.width must be >= 1, got 0"),
        ("C_astar_m10:m", "'m' is not m<robots>"),
        ("C_astar_m10:m0", "sim.num_robots must be"),
    ],
)
def test_bad_members_are_one_clear_error(member: str, message: str) -> None:
    with pytest.raises(ConfigError, match=message):
        member_spec(member)


def test_size_and_stream_keys_change_the_layout_and_the_tasks() -> None:
    spec = member_spec("A_astar_m10:s90:random:m40")
    sim = build_sim(spec)
    assert (sim.layout.width, sim.layout.height) == (90, 90)
    assert spec.tasks == member_spec("open300_direct_m100_random").tasks
    assert spec.navigator == SCENARIOS["A_astar_m10"].spec().navigator
    designated = member_spec("C256_astar_m100_random:s120:designated")
    big = build_sim(designated)
    assert (big.layout.width, big.layout.height) == (120, 120)
    assert designated.tasks == SCENARIOS["C_astar_m10"].spec().tasks
    # The same shelves as the registered layout at its own size: the size is the only change.
    assert member_spec("C_astar_m10:s60") == SCENARIOS["C_astar_m10"].spec()


def test_only_a_generated_layout_is_resized() -> None:
    read = dataclasses.replace(SCENARIOS["C_astar_m10"], layout={"name": "map", "path": "x.map"})
    with pytest.raises(ConfigError, match=r"s<size> resizes a generated layout .*'map'"):
        _resized(read, 90, "x:s90")


def test_a_member_twice_is_an_error() -> None:
    with pytest.raises(ConfigError, match=r"mix lists \['A_astar_m10'\] more than once"):
        mix_specs(["A_astar_m10", "B_astar_m10", "A_astar_m10"])


def test_generalist_mix_spans_fleets_maps_and_queues_and_holds_out_the_tests() -> None:
    specs = mix_specs(GENERALIST)
    robots = {s.sim.num_robots for s in specs}
    assert min(robots) <= 5
    assert max(robots) >= 1000
    assert {s.sim.queue_len for s in specs} == {5, 10}
    assert {s.sim.episode_mode for s in specs} == {"paper", "drain"}
    # The robot counts the generalist is evaluated on as unseen are not trained on.
    assert not robots & {30, 150, 300, 2000, 10_000}
    layouts = {str(s.layout) for s in specs}
    assert not any("movingai" in x or "warehouse_large" in x for x in layouts)


@pytest.mark.parametrize(
    ("overrides", "message"),
    [
        (["model=rtaw"], "use model=rtaw_plus with model.fleet_summary=true"),
        (["model=rtaw_plus"], "use model=rtaw_plus with model.fleet_summary=true"),
        (["model=rtaw_plus", "model.fleet_summary=true", "collector.envs_per_worker=3"],
         "collector.envs_per_worker=3 must be a multiple of the 2 mix members"),
    ],
)  # fmt: skip
def test_train_config_checks_the_mix(overrides: list[str], message: str) -> None:
    with pytest.raises(ConfigError, match=message):
        to_typed(compose("train", ["mix=[A_astar_m10,B_astar_m10:m20]", *overrides]))
