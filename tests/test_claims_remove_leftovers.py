"""A claimed output removes what a killed earlier atomic write of it (or of a file
written beside it) left, and nothing else; every writing command claims its output."""

from __future__ import annotations

from pathlib import Path

import pytest

from rtaw_marl.utils.runs import claim_file

pytestmark = pytest.mark.unit


def test_claim_removes_the_outputs_and_siblings_leftovers(tmp_path: Path) -> None:
    output = tmp_path / "results.json"
    leftovers = [tmp_path / ".results.json.ab12cd34.tmp", tmp_path / ".results.csv.zz_9x8y7.tmp"]
    kept = [tmp_path / ".other.json.ab12cd34.tmp", tmp_path / "results.json.ab12cd34.tmp",
            tmp_path / ".results.json.short.tmp"]  # fmt: skip
    for path in (*leftovers, *kept):
        path.write_bytes(b"x" * 1000)
    notes: list[str] = []
    with claim_file(output, siblings=("results.csv",), note=notes.append):
        assert not any(p.exists() for p in leftovers)
        assert all(p.exists() for p in kept)
    assert len(notes) == 1
    assert ".results.json.ab12cd34.tmp" in notes[0]
    assert ".results.csv.zz_9x8y7.tmp" in notes[0]


def test_nothing_left_nothing_said(tmp_path: Path) -> None:
    notes: list[str] = []
    with claim_file(tmp_path / "r.json", note=notes.append):
        pass
    assert notes == []


def test_rtaw_eval_removes_a_killed_writes_leftover(cli, tmp_path: Path) -> None:
    """rtaw-eval killed while writing results.json left its temporary: the next run of
    that output removes it and says so on stderr."""
    leftover = tmp_path / ".r.json.k3j4h5g6.tmp"
    leftover.write_bytes(b"{" * 3000)
    result = cli("eval", "scenario=poc", "policy=[mpdm]", "seeds=[0]", "output=r.json",
                 "progress=false")  # fmt: skip
    assert result.code == 0, result.err
    assert not leftover.exists()
    assert "note: removed what a killed earlier write of r.json left: .r.json.k3j4h5g6.tmp" in (
        result.err
    )
