"""Renamed config keys: ``env`` -> ``sim`` in every command, ``eval`` -> ``selection`` in
``rtaw-train``. An old key typed on a command line is one line naming the new one; what
was stored under the old names (configs, commands, results files) reads as today's."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from rtaw_marl.config import check_renamed, compose
from rtaw_marl.errors import ConfigError
from rtaw_marl.evaluation.results_file import read_results, upgrade_payload
from rtaw_marl.training import config as train_config
from rtaw_marl.utils.renamed import RENAMED, renamed_key, upgrade_command, upgrade_config

pytestmark = pytest.mark.unit

SIM = "(the simulator's keys; env names the PettingZoo env)"


@pytest.mark.parametrize(
    ("key", "message"),
    [
        ("env.num_robots", f"env.num_robots is now sim.num_robots {SIM}"),
        ("env", f"env is now sim {SIM}"),
        ("sim.num_robots", None),
        ("environment.x", None),
        ("envs_per_worker", None),
    ],
)
def test_renamed_key_names_the_new_key(key: str, message: str | None) -> None:
    assert renamed_key(key) == message


def test_rtaw_train_renames_both_sections() -> None:
    assert set(train_config.RENAMED) == {*RENAMED, "eval"}
    assert train_config.renamed_key("env.horizon") == f"env.horizon is now sim.horizon {SIM}"
    assert train_config.renamed_key("eval.seeds") == (
        "eval.seeds is now selection.seeds (the selection seeds' evaluation during training)"
    )


@pytest.mark.parametrize("app", ["eval", "train", "render", "view"])
@pytest.mark.parametrize("override", ["env.num_robots=5", "+env.num_robots=5", "~env.num_robots",
                                      "env@x.num_robots=5", "env=default"])  # fmt: skip
def test_every_command_with_the_simulator_refuses_env(app: str, override: str) -> None:
    with pytest.raises(ConfigError, match=r"^env(\.num_robots)? is now sim"):
        check_renamed(app, [override])
    with pytest.raises(ConfigError, match=r"is now sim"):
        compose(app, [override])


def test_only_train_renames_eval_and_lorr_has_no_simulator_group() -> None:
    check_renamed("eval", ["eval.seeds=[0]"])  # not rtaw-eval's old key: its own error later
    with pytest.raises(ConfigError, match="is now selection"):
        check_renamed("train", ["eval.seeds=[1000]"])
    check_renamed("lorr", ["env.num_robots=5"])  # rtaw-lorr never had the group
    check_renamed("eval", ["sim.num_robots=5", "--multirun", "policy=[mpdm]"])


def test_upgrade_config_renames_in_place_and_keeps_todays() -> None:
    old = {"env": {"num_robots": 3}, "layout": {"name": "open"}, "seeds": [0]}
    new = upgrade_config(old)
    assert list(new) == ["sim", "layout", "seeds"]
    assert new["sim"] == {"num_robots": 3}
    assert "env" in old  # a copy: the stored config is not touched
    assert upgrade_config(new) == new
    both = {"env": {"num_robots": 3}, "sim": {"num_robots": 5}}
    assert upgrade_config(both) == {"sim": {"num_robots": 5}}
    trained = train_config.upgrade_config({"env": {}, "eval": {"seeds": [1000]}, "seed": 0})
    assert list(trained) == ["sim", "selection", "seed"]


def test_upgrade_command_renames_old_keys_only() -> None:
    old = ["rtaw-train", "layout=A", "env.num_robots=10", "+env.horizon=5", "~env.noise_var",
           "env=default", "eval.every_frames=40960", "envs=1", "sim.queue_len=3",
           "tasks.path=env.csv"]  # fmt: skip
    assert upgrade_command(old) == [
        "rtaw-train", "layout=A", "sim.num_robots=10", "+sim.horizon=5", "~sim.noise_var",
        "sim=default", "eval.every_frames=40960", "envs=1", "sim.queue_len=3",
        "tasks.path=env.csv",
    ]  # fmt: skip
    assert train_config.upgrade_command(old)[6] == "selection.every_frames=40960"


def _results(group: str) -> dict:
    return {
        "config": {group: {"num_robots": 3}, "layout": {"name": "open"}, "policy": ["mpdm"]},
        "seeds": [0, 1],
        "policies": {"mpdm": {"ttd": [1.0, 2.0]}},
    }


def test_a_results_file_written_before_sim_reads_as_today(tmp_path: Path) -> None:
    """``config.env`` is read as ``config.sim`` (in the same place); the file stays."""
    path = tmp_path / "results.json"
    path.write_text(json.dumps(_results("env")))
    old = read_results(path)
    assert list(old.config) == ["sim", "layout", "policy"]
    new_path = tmp_path / "new.json"
    new_path.write_text(json.dumps(_results("sim")))
    assert read_results(new_path).config == old.config
    assert json.loads(path.read_text())["config"]["env"] == {"num_robots": 3}
    assert upgrade_payload(_results("env")) == _results("sim")
    assert upgrade_payload({"config": 1}) == {"config": 1}  # check_results says why
