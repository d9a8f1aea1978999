"""The typed config spine: schemas, YAML twins, unknown keys, and one builder for all."""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

import pytest
import yaml
from hydra.core.override_parser.overrides_parser import OverridesParser

from rtaw_marl.config import CONF_DIR, GROUPS, check_overrides, compose, to_typed
from rtaw_marl.config.store import APPS
from rtaw_marl.errors import ConfigError
from rtaw_marl.sim import builder

pytestmark = pytest.mark.integration

GROUP_DIRS = ("sim", "layout", "navigator", "tasks", "model", "algo", "collector")


def _twins() -> list[tuple[str, str]]:
    return [(g, p.stem) for g in GROUP_DIRS for p in sorted((CONF_DIR / g).glob("*.yaml"))]


def _twin(group: str, option: str) -> tuple[str, dict, dict]:
    """The schema a YAML option rests on, the values it and its parents set, and the
    values it inherits from a parent option (empty when it rests on the schema)."""
    text = yaml.safe_load((CONF_DIR / group / f"{option}.yaml").read_text())
    base = text["defaults"][0]
    own = {k: v for k, v in text.items() if k != "defaults"}
    if base.startswith("/schema/"):
        return base.split("/")[-1].split("@")[0], own, {}
    schema_name, parent, _ = _twin(group, base)  # another option of the same group
    return schema_name, {**parent, **own}, parent


@pytest.mark.parametrize(("group", "option"), _twins(), ids=lambda v: str(v))
def test_yaml_twin_is_its_schema_plus_what_it_sets(group: str, option: str) -> None:
    """Each YAML option composes to a schema's dataclass; it writes no default twice."""
    schema_name, text, inherited = _twin(group, option)
    schema = GROUPS[group][schema_name]
    overrides = [f"{group}={option}"]
    if (group, option) in (("layout", "file"), ("tasks", "file")):
        overrides.append(f"{group}.path=some/file")
    typed = getattr(to_typed(compose("train", overrides)), group)
    assert type(typed) is schema
    own = {k: v for k, v in text.items() if k not in ("defaults", "sim")}
    required = {
        f.name: own.get(f.name, "some/file")
        for f in dataclasses.fields(schema)
        if f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING
    }
    defaults = schema(**required)
    for field in dataclasses.fields(schema):
        expected = own.get(field.name, getattr(defaults, field.name))
        assert getattr(typed, field.name) == expected, field.name
    written = yaml.safe_load((CONF_DIR / group / f"{option}.yaml").read_text())
    for key, value in written.items():
        if key not in ("defaults", "sim", *required):
            before = inherited.get(key, getattr(defaults, key))
            assert value != before, f"{key} repeats what the option would have anyway"


@pytest.mark.parametrize("app", sorted(APPS))
def test_every_app_composes_to_its_dataclass(app: str) -> None:
    cfg = to_typed(compose(app))
    assert type(cfg) is APPS[app]


@pytest.mark.parametrize(
    "key",
    [
        "sim.num_robot",
        "layout.widht",
        "navigator.time_limit",  # astar has no time limit
        "tasks.sigmaa",
        "model.embed_dmi",
        "algo.lrr",
        "collector.worker",
        "selection.seed",
        "frame",
    ],
)
def test_unknown_key_in_any_group_is_one_line_exit_2(key: str, cli, tmp_path: Path) -> None:
    """``rtaw-train +algo.lrr=1``: one line naming the key and the valid ones, exit 2."""
    result = cli("train", f"+{key}=1", f"output_dir={tmp_path}")
    assert result.code == 2
    lines = result.err.strip().splitlines()
    assert len(lines) == 1, result.err
    assert f"unknown config key '{key}'" in lines[0]
    # An option with no settable keys says so instead of offering its fixed name.
    assert ("valid keys there:" in lines[0]) != ("takes no keys" in lines[0])
    assert "name" not in lines[0].partition(";")[2]


@pytest.mark.parametrize("app", ["eval", "render"])
def test_unknown_key_in_eval_and_render(app: str, cli) -> None:
    result = cli(app, "+sim.bogus=3")
    assert result.code == 2
    assert result.err.startswith("error: unknown config key 'sim.bogus'; valid keys there: num_")


def test_wrong_type_is_one_line(cli) -> None:
    result = cli("eval", "sim.num_robots=many")
    assert result.code == 2
    assert result.err.strip() == (
        "error: config key 'sim.num_robots': Value 'many' of type 'str' could not be "
        "converted to Integer"
    )


def test_compose_errors_are_config_errors() -> None:
    with pytest.raises(ConfigError, match=r"unknown config key 'algo\.lrr'"):
        to_typed(compose("train", ["+algo.lrr=1"]))
    with pytest.raises(ConfigError, match="available: astar, cbs, direct, pibt, sipp"):
        compose("train", ["navigator=dijkstra"])


def test_the_override_check_parses_only_boolean_keys(monkeypatch: pytest.MonkeyPatch) -> None:
    """``seeds='${range:0,100000}'`` reaches the check expanded, and parsing a list is
    quadratic in its length (100k seeds: minutes): only a boolean key's override is
    parsed, so the seeds are never re-parsed whatever their number."""
    parsed: list[list[str]] = []
    parse = OverridesParser.parse_overrides

    def recording(self: OverridesParser, overrides: list[str]) -> Any:
        parsed.append(list(overrides))
        return parse(self, overrides)

    monkeypatch.setattr(OverridesParser, "parse_overrides", recording)
    cfg = compose("eval", ["scenario=poc", "seeds=[0,1]"])
    seeds = f"seeds={list(range(100_000))}"
    parsed.clear()  # Hydra's own parse of the composition's overrides
    check_overrides(cfg, [seeds, "scenario=poc", "sim.num_robots=3", "progress=true"])
    assert parsed == [["progress=true"]]
    with pytest.raises(ConfigError, match=r"^lower_bound must be true or false, got 'off'$"):
        check_overrides(cfg, [seeds, "+lower_bound=off"])
    assert parsed[-1] == ["+lower_bound=off"]


# --------------------------------------------------------------------------- one builder
PARAMS = [
    "layout=warehouse",
    "layout.width=24",
    "layout.height=20",
    "layout.shelf_width=4",
    "layout.shelf_height=1",
    "layout.aisle_x=3",
    "layout.aisle_y=2",
    "layout.highway_every=2",
    "layout.highway_width=3",
    "layout.margin=3",
    "layout.station_spacing=3",
    "navigator=cbs",
    "navigator.time_limit=1.5",
    "navigator.max_nodes=7",
    "tasks=clustered",
    "tasks.num_clusters=3",
    "tasks.sigma=2.5",
    "sim.num_robots=3",
    "sim.num_tasks=8",
    "sim.queue_len=3",
]


@pytest.fixture
def built_specs(monkeypatch) -> list[builder.SimSpec]:
    """Every spec the one builder receives while the test runs."""
    specs: list[builder.SimSpec] = []
    original = builder.SimFactory.__init__

    def spy(self, spec: builder.SimSpec) -> None:
        specs.append(spec)
        original(self, spec)

    monkeypatch.setattr(builder.SimFactory, "__init__", spy)
    return specs


def _assert_params_reached(specs: list[builder.SimSpec]) -> None:
    assert specs, "no simulator was built through rtaw_marl.sim.builder"
    for spec in specs:
        layout, nav, tasks = spec.layout, spec.navigator, spec.tasks
        assert (layout.name, layout.width, layout.height) == ("warehouse", 24, 20)
        assert (layout.shelf_width, layout.shelf_height) == (4, 1)
        assert (layout.aisle_x, layout.aisle_y, layout.margin) == (3, 2, 3)
        assert (layout.highway_every, layout.highway_width, layout.station_spacing) == (2, 3, 3)
        assert (nav.name, nav.time_limit, nav.max_nodes) == ("cbs", 1.5, 7)
        assert (tasks.name, tasks.num_clusters, tasks.sigma) == ("clustered", 3, 2.5)
        assert (spec.sim.num_robots, spec.sim.num_tasks, spec.sim.queue_len) == (3, 8, 3)
        executor = spec.navigator.executor()
        assert (executor.time_limit, executor.max_nodes) == (1.5, 7)


def test_every_parameter_reaches_the_simulator_from_rtaw_eval(cli, built_specs) -> None:
    result = cli("eval", *PARAMS, "policy=[mpdm]", "seeds=[0]", "progress=false")
    assert result.code == 0, result.err
    _assert_params_reached(built_specs)


def test_every_parameter_reaches_the_simulator_from_rtaw_render(cli, built_specs) -> None:
    result = cli("render", *PARAMS, "policy=mpdm", "output=e.gif", "max_frames=5000")
    assert result.code == 0, result.err
    _assert_params_reached(built_specs)


def test_every_parameter_reaches_the_simulator_from_rtaw_train(cli, built_specs, tmp_path) -> None:
    """Regression: training used to keep only navigator.name and drop its budgets."""
    result = cli(
        "train", *PARAMS, "frames=48", "algo.frames_per_batch=48", "algo.minibatch_size=16",
        "collector.envs_per_worker=4", "selection.seeds=[1000]", "selection.every_frames=48",
        f"output_dir={tmp_path / 'run'}", "progress=false",
    )  # fmt: skip
    assert result.code == 0, result.err
    # The evaluation envs, the MPDM reference and the collector's envs.
    assert len(built_specs) >= 3
    _assert_params_reached(built_specs)


def test_user_config_folder_adds_options(cli, tmp_path: Path) -> None:
    """``hydra.searchpath`` adds a user's options, typed by the same schemas."""
    conf = tmp_path / "my_conf" / "layout"
    conf.mkdir(parents=True)
    (conf / "tiny.yaml").write_text(
        "defaults:\n  - /schema/layout/open@_here_\n  - _self_\n\nwidth: 7\nheight: 5\n"
    )
    result = cli(
        "eval", f"hydra.searchpath=[file://{conf.parent}]", "layout=tiny", "tasks=random",
        "sim.num_robots=2", "sim.num_tasks=6", "policy=[mpdm]", "seeds=[0]", "progress=false",
    )  # fmt: skip
    assert result.code == 0, result.err
    assert "open_7x5" in result.out
    (conf / "typo.yaml").write_text(
        "defaults:\n  - /schema/layout/open@_here_\n  - _self_\n\nwidht: 7\n"
    )
    result = cli("eval", f"hydra.searchpath=[file://{conf.parent}]", "layout=typo")
    assert result.code == 2
    assert "widht" in result.err


@pytest.mark.parametrize("name", ["sipp", "cbs", "pibt"])
def test_a_navigator_sets_the_simulator_keys_its_option_names(name: str) -> None:
    """``navigator=sipp`` (a stored node, no YAML) sets exactly the option's
    ``sim_defaults``, which ``SimSpec.of(navigator=...)`` applies too; a key the user
    gives still wins."""
    from rtaw_marl.config import compose
    from rtaw_marl.sim.builder import SimSpec
    from rtaw_marl.sim.options import NAVIGATORS

    defaults = dict(NAVIGATORS[name].sim_defaults)
    assert defaults == {"noise_mean": 0.0, "noise_var": 0.0}
    cfg = compose(config_name="eval", overrides=[f"navigator={name}"])
    assert {k: cfg.sim[k] for k in defaults} == defaults
    spec = SimSpec.of(navigator=name)
    assert {k: getattr(spec.sim, k) for k in defaults} == defaults
    given = compose(config_name="eval", overrides=[f"navigator={name}", "sim.noise_mean=3.0"])
    assert given.sim.noise_mean == 3.0
