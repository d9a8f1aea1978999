"""``--help`` of every Hydra command, and shell completion (``-sc``).

All in-process through the ``cli`` fixture (the console entry point's ``main``), except
one run of the installed ``rtaw-eval`` script, the wrapper a shell's completion calls.
"""

from __future__ import annotations

import dataclasses
import subprocess
import sys
from pathlib import Path

import pytest

from rtaw_marl.cli.completion import own_words
from rtaw_marl.config.help import GROUP_DOCS, app_groups
from rtaw_marl.config.reference import attribute_docs
from rtaw_marl.config.store import APPS, GROUPS
from rtaw_marl.evaluation.config import EvalConfig
from rtaw_marl.sim.config import SimConfig

pytestmark = pytest.mark.integration

RTAW_EVAL = Path(sys.executable).with_name("rtaw-eval")


def _groups_listed(text: str) -> set[str]:
    """The groups of the help's groups section (``layout: the warehouse map``)."""
    section = text.partition("== Config groups")[2].partition("== Keys")[0]
    return {
        line.partition(":")[0]
        for line in section.splitlines()[1:]
        if line and not line.startswith(" ")
    }


def _key_line(text: str, setting: str) -> str:
    (line,) = [ln for ln in text.splitlines() if ln.strip().startswith(f"{setting} ")]
    return line


def test_eval_help_lists_its_groups_and_no_training_group(cli) -> None:
    result = cli("eval", "--help")
    assert result.code == 0
    assert result.out.startswith("rtaw-eval: evaluate")
    listed = _groups_listed(result.out)
    assert listed == set(app_groups("eval"))
    assert {"sim", "layout", "navigator", "tasks", "scenario", "row"} <= listed
    # Training groups and Hydra's internal schemas are not offered.
    for foreign in ("algo", "collector", "model", "zoo", "schema"):
        assert f"\n{foreign}" not in result.out
    assert "schema/" not in result.out


def test_eval_help_describes_keys_from_the_schemas(cli) -> None:
    """Each key's line: its current value, then the start of its ``Attributes:`` entry."""
    result = cli("eval", "--help")
    sim_docs, eval_docs = attribute_docs(SimConfig), attribute_docs(EvalConfig)
    assert sim_docs["queue_len"].replace("``", "")[:30] in _key_line(result.out, "sim.queue_len=10")
    assert eval_docs["seeds"][:30] in _key_line(result.out, "seeds=[0,1,2,3,4]")
    assert "baselines.lookahead_horizon=3" in result.out
    assert "search.width=2" in result.out  # a section's keys, each on its line
    # Every top-level key of the schema has a line.
    for field in dataclasses.fields(EvalConfig):
        if field.name not in ("sim", "layout", "navigator", "tasks", "baselines", "search"):
            assert f"\n  {field.name}=" in result.out, field.name


def test_train_help_shows_its_groups_and_the_overrides(cli) -> None:
    """``rtaw-train scenario=poc --help``: training groups, the current choices starred,
    the values the overrides compose to; no evaluation-only group."""
    result = cli("train", "scenario=poc", "--help")
    assert result.code == 0
    listed = _groups_listed(result.out)
    assert {"model", "algo", "collector", "zoo"} <= listed
    assert not listed & {"row", "experiment"}
    assert "*poc" in result.out
    assert "*direct" in result.out
    assert "sim.num_robots=2 " in result.out  # poc's fleet, not the default 10
    assert "algo.lr=" in result.out


@pytest.mark.parametrize("app", sorted(APPS))
def test_every_command_has_its_own_help(app: str, cli) -> None:
    """Every Hydra command (a new one too) has a help section naming it, and every
    group it takes has a one-line description."""
    result = cli(app, "--help")
    assert result.code == 0, result.err
    assert result.out.startswith(f"rtaw-{app}: ")
    assert "powered by Hydra" not in result.out
    for group in app_groups(app):
        assert group in GROUP_DOCS, f"add a line for {group!r} to GROUP_DOCS"
    assert set(app_groups(app)) <= set(GROUPS) | {"scenario", "row", "experiment", "zoo", "recipe"}


def test_shell_completion_install_prints_the_script(cli) -> None:
    result = cli("eval", "-sc", "install=bash")
    assert result.code == 0
    assert "hydra_bash_completion" in result.out
    assert result.out.rstrip().endswith("-F hydra_bash_completion rtaw-eval")
    assert "Traceback" not in result.err


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--shell-completion"], "--shell-completion needs one of install=SHELL"),
        (["-sc", "install=bash", "query=bash"], "--shell-completion needs one of"),
        (["-sc", "install=bsh"], "unknown shell 'bsh'; available: bash, fish, zsh; did you"),
    ],
)
def test_bad_shell_completion_request_is_one_line(args: list[str], message: str, cli) -> None:
    result = cli("eval", *args)
    assert result.code == 2
    (line,) = result.err.strip().splitlines()
    assert line.startswith("error: ")
    assert message in line
    assert "Traceback" not in result.err + result.out


def test_completion_query_offers_only_the_commands_groups(cli, monkeypatch) -> None:
    monkeypatch.setenv("COMP_LINE", "rtaw-eval ")
    words = cli("eval", "-sc", "query=bash").out.split()
    assert {"navigator=", "scenario=", "seeds.", "policy."} <= set(words)
    assert not [w for w in words if w.startswith(("algo", "collector", "zoo", "schema"))]
    monkeypatch.setenv("COMP_LINE", "rtaw-train ")
    words = cli("train", "-sc", "query=bash").out.split()
    assert {"algo=", "collector=", "model="} <= set(words)
    monkeypatch.setenv("COMP_LINE", "rtaw-eval navigator=s")
    assert cli("eval", "-sc", "query=bash").out.split() == ["navigator=sipp"]


def test_own_words_keeps_keys_and_hydra() -> None:
    words = ["+zoo=", "algo=", "schema/", "sim.", "hydra/", "~row", "seeds="]
    assert own_words("eval", words) == ["sim.", "hydra/", "~row", "seeds="]


def test_console_script_prints_the_completion_script(tmp_path: Path) -> None:
    """The installed wrapper (what ``eval "$(rtaw-eval -sc install=bash)"`` runs)."""
    proc = subprocess.run(
        [str(RTAW_EVAL), "-sc", "install=bash"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode == 0, proc.stderr
    assert "complete -o nospace -o default -F hydra_bash_completion rtaw-eval" in proc.stdout
    assert proc.stderr == ""
