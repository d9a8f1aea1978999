"""An output never one of its inputs, and a killed write's leftovers found by name."""

from __future__ import annotations

from pathlib import Path

import pytest

from rtaw_marl.cli.common import typed
from rtaw_marl.config import compose
from rtaw_marl.errors import ConfigError
from rtaw_marl.utils.atomic import atomic_write
from rtaw_marl.utils.stale import remove_stale_temps, stale_temps
from rtaw_marl.viz.output_file import claimed_output, config_inputs, refuse_inputs, same_file

pytestmark = pytest.mark.unit


def test_same_file_through_names_and_links(tmp_path: Path, monkeypatch) -> None:
    monkeypatch.chdir(tmp_path)
    real = tmp_path / "s.html"
    real.write_text("x", encoding="utf-8")
    (tmp_path / "sub").mkdir()
    (tmp_path / "link.html").symlink_to(real)
    (tmp_path / "hard.html").hardlink_to(real)
    for name in ("s.html", "./s.html", "sub/../s.html", str(real), "link.html", "hard.html"):
        assert same_file(name, real), name
    assert not same_file("other.html", real)  # not there yet: another file
    assert not same_file("sub/s.html", real)


def test_config_inputs_are_the_existing_files_it_names(tmp_path: Path, monkeypatch) -> None:
    monkeypatch.chdir(tmp_path)
    for name in ("a.json", "b.json", "v.html"):
        (tmp_path / name).write_text("{}", encoding="utf-8")
    cfg = typed(
        compose(config_name="view", overrides=["schedule=[a.json,b.json]", "output=v.html",
                                               "title=b.json"])
    )  # fmt: skip
    assert config_inputs(cfg) == [("schedule", Path("a.json")), ("schedule", Path("b.json"))]
    with pytest.raises(ConfigError, match=r"output=b.json is the same file as schedule=b.json"):
        refuse_inputs("b.json", config_inputs(cfg))
    refuse_inputs("v.html", config_inputs(cfg))


def test_stale_temps_are_only_this_outputs(tmp_path: Path) -> None:
    """.<name>.XXXXXXXX.tmp with mkstemp's 8 characters: nothing else."""
    out = tmp_path / "v.html"
    mine = [".v.html.abcd_123.tmp", ".v.html.zzzzzzzz.tmp"]
    others = [".v.html.abc.tmp", ".v.html.abcdefghi.tmp", ".v.html.ABCDEFGH.tmp",
              ".w.html.abcdefgh.tmp", "v.html.abcdefgh.tmp", ".v.html.abcdefgh.tmpx",
              ".v.htmlXabcdefgh.tmp"]  # fmt: skip
    for name in mine + others:
        (tmp_path / name).write_text("x", encoding="utf-8")
    (tmp_path / ".v.html.folder00.tmp").mkdir()  # not a file: left alone
    assert [p.name for p in stale_temps(out)] == sorted(mine)
    assert [p.name for p in remove_stale_temps(out)] == sorted(mine)
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted([*others, ".v.html.folder00.tmp"])
    assert stale_temps(tmp_path / "missing" / "v.html") == []


def test_the_pattern_is_atomic_writes_own(tmp_path: Path) -> None:
    """A temporary file atomic_write really makes (kept by a write that fails midway,
    as a kill would keep it) matches."""
    out = tmp_path / "v.html"

    def write(fh) -> None:
        (leftover,) = list(tmp_path.glob(".v.html.*.tmp"))
        assert stale_temps(out) == [leftover]
        raise KeyboardInterrupt  # cleaned up by atomic_write itself, unlike kill -9

    with pytest.raises(KeyboardInterrupt):
        atomic_write(out, write)


def test_claimed_output_refuses_an_input_and_cleans_its_leftovers(tmp_path: Path) -> None:
    out = tmp_path / "v.html"
    (tmp_path / ".v.html.abcdefgh.tmp").write_text("x", encoding="utf-8")
    notes: list[str] = []
    refused = claimed_output(out, [("schedule", out)], progress=notes.append)
    with pytest.raises(ConfigError, match="is the same file as schedule="), refused:
        pass  # pragma: no cover
    assert (tmp_path / ".v.html.abcdefgh.tmp").exists()  # refused: nothing touched
    with claimed_output(out, [], progress=notes.append) as held:
        assert held == out
        assert (tmp_path / ".v.html.lock").exists()
    assert notes == ["removed what a killed earlier write of v.html left: .v.html.abcdefgh.tmp"]
    assert sorted(p.name for p in tmp_path.iterdir()) == []
