"""The simulator groups' defaults are written once (``rtaw_marl.sim.builder.
DEFAULT_OPTIONS``): SimSpec builds them, and every command's defaults list takes them
from ``/setting/NAME`` instead of naming options itself."""

from __future__ import annotations

import pytest
import yaml

from rtaw_marl.config import compose, to_typed
from rtaw_marl.config.store import CONF_DIR, SETTINGS
from rtaw_marl.sim.builder import DEFAULT_OPTIONS, SimSpec

pytestmark = pytest.mark.unit

#: Which setting each command starts from.
APPS = {"eval": "default", "train": "default", "render": "watch", "view": "watch"}


@pytest.mark.parametrize(("app", "setting"), APPS.items())
def test_each_command_starts_from_one_setting(app: str, setting: str) -> None:
    defaults = yaml.safe_load((CONF_DIR / f"{app}.yaml").read_text())["defaults"]
    assert f"/setting/{setting}@_here_" in defaults
    named = [e for e in defaults if isinstance(e, dict) and set(e) & set(DEFAULT_OPTIONS)]
    assert named == [], f"{app}.yaml names simulator options itself: {named}"
    cfg = compose(app, [])
    chosen = {"layout": cfg.layout.name, "navigator": cfg.navigator.name, "tasks": cfg.tasks.name}
    assert chosen == {group: SETTINGS[setting][group] for group in chosen}


def test_simspec_builds_the_default_setting() -> None:
    """What rtaw-eval composes with no argument is what SimSpec() builds."""
    cfg = to_typed(compose("eval", []))
    spec = SimSpec()
    assert (cfg.layout, cfg.navigator, cfg.tasks, cfg.sim) == (
        spec.layout, spec.navigator, spec.tasks, spec.sim,
    )  # fmt: skip


def test_a_scenario_still_chooses_its_navigator_in_the_watching_commands() -> None:
    """rtaw-view starts from SIPP, but scenario=C_astar_m100 (A*) wins, as before."""
    assert compose("view", []).navigator.name == "sipp"
    assert compose("view", ["scenario=C_astar_m100"]).navigator.name == "astar"
    assert compose("view", ["navigator=pibt"]).navigator.name == "pibt"
