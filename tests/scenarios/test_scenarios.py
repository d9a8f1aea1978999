"""One source per setting: the scenario registry, its ``scenario=`` and ``row=`` options
in Hydra's ConfigStore, and the same simulator from every way of naming it."""

from __future__ import annotations

import pytest
from hydra.core.config_store import ConfigStore
from omegaconf import OmegaConf

from rtaw_marl.config import CONF_DIR, compose, group_options, to_typed
from rtaw_marl.config.scenarios import LORR, lorr_node, row_node, scenario_node
from rtaw_marl.errors import ConfigError
from rtaw_marl.policies.pretrained.registry import PRETRAINED
from rtaw_marl.scenarios import EVAL_SEEDS, ROWS, SCENARIOS, scenario
from rtaw_marl.sim.builder import SimSpec, build_sim

pytestmark = pytest.mark.integration


def _stored(group: str, name: str) -> dict:
    node = ConfigStore.instance().load(f"{group}/{name}.yaml")
    assert node.package == "_global_"
    return OmegaConf.to_container(node.node, resolve=False)  # type: ignore[return-value]


def test_scenario_and_row_options_are_the_registry() -> None:
    """``scenario=`` and ``row=`` offer exactly the registry's names, each stored as its
    entry's node, and no YAML file shadows them."""
    assert group_options("scenario") == sorted([*SCENARIOS, LORR])
    assert group_options("row") == sorted(ROWS)
    for name, s in SCENARIOS.items():
        assert _stored("scenario", name) == scenario_node(s)
    assert _stored("scenario", LORR) == lorr_node()
    for row in ROWS:
        assert _stored("row", row) == row_node(row)
    assert not [*CONF_DIR.glob("scenario/*.yaml"), *CONF_DIR.glob("row/*.yaml")]


def test_a_scenario_node_chooses_its_options_and_sets_its_keys() -> None:
    assert scenario_node(SCENARIOS["default"]) == {}
    assert scenario_node(SCENARIOS["C256_astar_m1000_random"]) == {
        "defaults": [
            {"override /layout": "C"},
            {"override /navigator": "astar"},
            {"override /tasks": "random"},
        ],
        "sim": {"num_robots": 1000, "num_tasks": 5000, "episode_mode": "paper"},
        "layout": {"width": 256, "height": 256},
    }
    assert row_node("A_m100") == {
        "defaults": [{"override /scenario": "A_astar_m100"}],
        "pretrained": ["A_astar_m100_long_plus", "A_astar_m100_long"],
    }


@pytest.mark.parametrize("name", list(SCENARIOS))
@pytest.mark.parametrize("app", ["eval", "train"])
def test_command_line_and_python_build_the_same_scenario(name: str, app: str) -> None:
    spec = to_typed(compose(config_name=app, overrides=[f"scenario={name}"])).sim_spec()
    assert spec == SCENARIOS[name].spec()
    # The override list names the same setting.
    assert (
        to_typed(compose(config_name=app, overrides=SCENARIOS[name].overrides())).sim_spec() == spec
    )


@pytest.mark.parametrize("row", list(ROWS))
def test_a_row_is_its_scenario_and_its_shipped_policies(row: str) -> None:
    cfg = compose(config_name="eval", overrides=[f"row={row}"])
    s = SCENARIOS[ROWS[row]]
    assert to_typed(cfg).sim_spec() == s.spec()
    assert list(cfg.pretrained) == list(s.policies.values())


def test_every_shipped_policy_a_scenario_names_is_registered() -> None:
    named = {p for s in SCENARIOS.values() for p in s.policies.values()}
    assert named <= set(PRETRAINED), sorted(named - set(PRETRAINED))


def test_evaluation_seeds_are_not_selection_seeds() -> None:
    assert tuple(range(20)) == EVAL_SEEDS
    assert all(max(s.seeds) < 1000 for s in SCENARIOS.values())


@pytest.mark.parametrize("option", group_options("layout"))
def test_layout_names_mean_the_same_in_python(option: str) -> None:
    """``layout=C`` and ``SimSpec.of(layout="C")`` are the same layout (``file`` needs a path)."""
    overrides = [f"layout={option}"] + (["layout.path=maps/x.map"] if option == "file" else [])
    hydra = to_typed(compose(config_name="eval", overrides=overrides)).sim_spec().layout
    python = SimSpec.of(layout="maps/x.map" if option == "file" else option).layout
    assert python == hydra


@pytest.mark.parametrize("option", group_options("navigator"))
def test_navigator_names_mean_the_same_in_python(option: str) -> None:
    """``navigator=sipp`` turns the noise off on the command line and in Python alike."""
    hydra = to_typed(compose(config_name="eval", overrides=[f"navigator={option}"])).sim_spec()
    assert SimSpec.of(navigator=option) == hydra
    # A key given explicitly wins over the navigator's defaults, as on the command line.
    given = to_typed(
        compose(config_name="eval", overrides=[f"navigator={option}", "sim.noise_mean=0.5"])
    ).sim_spec()
    assert SimSpec.of({"noise_mean": 0.5}, navigator=option) == given


def test_unknown_names_list_the_valid_ones() -> None:
    with pytest.raises(ConfigError, match=r"unknown scenario 'C_astar'.*C_astar_m10"):
        scenario("C_astar")
    with pytest.raises(ConfigError, match=r"unknown layout 'Z'.*A, B, C, D, E"):
        SimSpec.of(layout="Z")


def test_with_sim_changes_only_what_it_is_given() -> None:
    base = SCENARIOS["C_astar_m10"]
    paper = base.with_sim(episode_mode="paper")
    assert paper.spec().sim.episode_mode == "paper"
    assert paper.spec().sim.num_robots == 10
    assert base.spec().sim.episode_mode == "drain"


@pytest.mark.parametrize("name", ["C_astar_m10", "poc", "open300_direct_m100_random"])
def test_the_env_takes_a_scenario_name(name: str) -> None:
    from rtaw_marl import warehouse_v1

    env = warehouse_v1.env(scenario=name)
    assert env.unwrapped.sim.config == SCENARIOS[name].spec().sim
    assert (
        env.unwrapped.sim.layout.describe() == build_sim(SCENARIOS[name].spec()).layout.describe()
    )
    # Arguments given beside it win, as command-line overrides beat scenario=NAME.
    assert warehouse_v1.env(scenario=name, num_tasks=3).unwrapped.sim.config.num_tasks == 3


def test_the_env_and_the_command_line_mean_the_same_layout_c() -> None:
    from rtaw_marl import warehouse_v1

    env = warehouse_v1.env(layout="C")
    hydra = to_typed(compose(config_name="eval", overrides=["layout=C"])).sim_spec()
    assert env.unwrapped.sim.layout.describe() == build_sim(hydra).layout.describe()
