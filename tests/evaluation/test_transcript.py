"""rtaw-eval's report: saved beside results.json, and kept apart from progress output."""

from __future__ import annotations

import io
import json
from pathlib import Path

import pytest

from rtaw_marl.cli.eval import run
from rtaw_marl.config import compose
from rtaw_marl.evaluation.transcript import Transcript, progress_shown, transcript_path

pytestmark = pytest.mark.integration

TINY = ["sim.num_tasks=20", "sim.num_robots=3", "policy=[mpdm,rbts]", "seeds=[0,1]"]


class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_the_printed_report_is_saved_beside_results_json(cli, tmp_path: Path) -> None:
    """stdout holds the report and nothing else; results.txt is the same text, and its
    table rows are those of results.json. Progress (stderr, not a terminal here) draws
    no bar."""
    out = tmp_path / "run" / "results.json"
    result = cli("eval", *TINY, f"output={out}", "progress=true")
    assert result.code == 0, result.err
    saved = (tmp_path / "run" / "results.txt").read_text()
    assert result.out == saved
    assert "| policy | TTD ± 95% CI |" in saved
    assert saved.startswith("layout ")
    assert saved.endswith(f"results: {out}\nepisodes: {out.with_suffix('.csv')}\n")
    data = json.loads(out.read_text())
    for name in ("mpdm", "rbts"):
        (line,) = [row for row in saved.splitlines() if row.startswith(f"| {name} |")]
        mean = sum(data["policies"][name]["ttd"]) / 2
        assert line.split(" | ")[1].startswith(f"{mean:.2f} ± ")
    assert "\r" not in result.err
    assert "dec/s" not in result.err
    assert not list(out.parent.glob(".*tmp"))


def test_a_hydra_run_folder_gets_results_txt(cli, tmp_path: Path) -> None:
    """Without output=, the report lands in the Hydra run folder beside results.json."""
    result = cli("eval", *TINY, "progress=false", f"hydra.run.dir={tmp_path / 'hy'}")
    assert result.code == 0, result.err
    assert (tmp_path / "hy" / "results.txt").read_text() == result.out


def test_the_bar_is_drawn_on_a_terminal_only(monkeypatch, tmp_path: Path, capsys) -> None:
    """On a terminal stderr the bar is drawn there, never on stdout; progress=false
    draws none even on a terminal."""
    for progress, drawn in (("true", True), ("false", False)):
        terminal = _Terminal()
        monkeypatch.setattr("sys.stderr", terminal)
        out = tmp_path / progress / "results.json"
        run(compose("eval", [*TINY, f"output={out}", f"progress={progress}"]))
        assert ("dec/s" in terminal.getvalue()) is drawn
        stdout = capsys.readouterr().out
        assert "dec/s" not in stdout
        assert stdout == transcript_path(out).read_text()


def test_progress_shown_needs_a_request_and_a_terminal() -> None:
    assert progress_shown(True, _Terminal())
    assert not progress_shown(False, _Terminal())
    assert not progress_shown(True, io.StringIO())


def test_transcript_path_never_is_the_results_file() -> None:
    assert transcript_path("a/results.json") == Path("a/results.txt")
    assert transcript_path("a/out.txt") == Path("a/out.txt.txt")


def test_transcript_prints_and_saves_the_same_text(tmp_path: Path) -> None:
    stream = io.StringIO()
    report = Transcript(stream)
    report.print("| a |\n|---|")
    report.print("done")
    assert (
        report.save(tmp_path / "t.txt").read_text() == stream.getvalue() == "| a |\n|---|\ndone\n"
    )
