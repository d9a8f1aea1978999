"""experiments/paper_tables.py: table formatting on fake TTDs and ``--reuse``."""

from __future__ import annotations

import json
import sys

import numpy as np
import pytest
from experiment_scripts import load_experiment

from rtaw_marl.errors import ConfigError

pt = load_experiment("paper_tables")

#: Mean TTD per policy of the fake evaluations (lower is better).
MEANS = {"MPDM": 1000, "RBTS": 990, "lookahead": 920, "hungarian": 1010, "hindsight": 850,
         "RTAW": 970, "RTAW+": 880}  # fmt: skip


def fake_ttd(labels, seeds) -> dict[str, list[float]]:
    """Per-seed TTDs around ``MEANS`` (exactly, for an even number of seeds)."""
    noise = 30.0 * (-1.0) ** np.arange(len(seeds))  # common to all policies: paired
    return {p: list(MEANS[p] + noise) for p in labels}


@pytest.fixture
def fake(monkeypatch, tmp_path):
    """Data and results in ``tmp_path``, every learned checkpoint "present", and a fake
    ``evaluate_setting`` that records the policies each job asks for."""
    calls: list[tuple[str, tuple[str, ...]]] = []

    def evaluate_setting(job):
        calls.append((str(job["key"]), tuple(job["policies"])))
        ttd = fake_ttd(job["policies"], job["seeds"])
        return {"key": job["key"], "ttd": ttd, "seconds": dict.fromkeys(ttd, 0.1)}

    monkeypatch.setattr(pt, "evaluate_setting", evaluate_setting)
    monkeypatch.setattr(pt, "learned_entry", lambda scenario, label: scenario + pt.LEARNED[label])
    monkeypatch.setattr(pt, "DATA", tmp_path / "data")
    results = tmp_path / "results.md"
    names = ("table1_paper", "table1_drain", "table2", "transfer", "navigators")
    results.write_text("".join(f"<!-- BEGIN {n} -->\nold\n<!-- END {n} -->\n" for n in names))
    monkeypatch.setattr(pt, "RESULTS", results)
    return calls


def test_section_has_both_tables_and_pooled_lines():
    rows = {f"row {i}": {"ttd": fake_ttd(MEANS, [0, 1, 2, 3])} for i in range(3)}
    text = pt.section(rows, list(rows))
    means, comparisons, summary = text.split("\n\n")
    assert means.splitlines()[0].startswith("| setting | MPDM | RBTS | lookahead | hungarian")
    assert "| RTAW | RTAW+ | hindsight share: lookahead / RTAW / RTAW+ |" in means
    assert "| row 0 | " in means
    assert "RTAW+ vs lookahead" in comparisons
    assert "RTAW vs the strongest rule" in comparisons
    assert "lookahead: " in comparisons  # the strongest rule is named
    assert "- RTAW+ vs MPDM, pooled: +12.0% [" in summary
    assert "- RTAW+ vs the strongest rule, pooled:" in summary
    assert "- RTAW+ beats lookahead on 3 of 3 rows (significantly on 3;" in summary
    assert "- hindsight share, pooled (lookahead / RTAW / RTAW+): 53% / 20% / 80%" in summary
    assert ">= +10% vs MPDM pooled: met (+12.0%); >= 70% hindsight share pooled: met (80%)" in (
        summary
    )


def test_missing_policies_show_a_dash():
    rows = {"r": {"ttd": fake_ttd(["MPDM", "RBTS", "lookahead", "hungarian", "RTAW"], [0, 1])}}
    text = pt.section(rows, ["r"])
    assert "| r | 1000 | 990 | 920 | 1010 | - | 970 | - | - / - / - |" in text
    assert "| r | - | - | - | - | +3.0% [+3.0, +3.0]* | lookahead: -5.4% [-5.4, -5.4]* |" in text
    assert "- RTAW+ vs MPDM, pooled: -" in text
    assert "RTAW+ beats MPDM on 0 of 0 rows" in text


def test_reuse_evaluates_only_the_missing_policies(fake, tmp_path):
    seeds = [0, 1]
    rules = fake_ttd(["MPDM", "RBTS", "lookahead", "hungarian", "hindsight"], seeds)
    stale = {**rules, "RTAW": [1.0, 2.0]}  # a learned column is never reused
    rows = {f"{label}, M={m}": stale for label, *_ in pt.ROWS for m in (10, 100)}
    pt.DATA.mkdir()
    (pt.DATA / "table1_paper.json").write_text(json.dumps({"seeds": seeds, "rows": rows}))
    assert pt.main(["table1", "--seeds", "2", "--reuse"]) == 0
    paper = [c for c in fake if c[0] in rows][: len(rows)]
    assert {policies for _, policies in paper} == {("RTAW", "RTAW+")}
    assert len(fake) == 2 * len(rows)  # drain has no stored file: everything is evaluated
    assert fake[-1][1] == ("MPDM", "RBTS", "lookahead", "hungarian", "hindsight", "RTAW", "RTAW+")
    saved = json.loads((pt.DATA / "table1_paper.json").read_text())
    row = saved["rows"]["A* layout C, M=100"]
    assert list(row) == list(pt.ORDER)
    assert row["MPDM"] == rules["MPDM"]
    assert row["RTAW"] != [1.0, 2.0]
    assert "RTAW+ vs hungarian" in pt.RESULTS.read_text()


def test_reuse_ignores_a_file_of_other_seeds(fake, capsys):
    pt.DATA.mkdir()
    (pt.DATA / "navigators.json").write_text(json.dumps({"seeds": [0], "rows": {}}))
    pt.navigators([0, 1], workers=1, hindsight=False, reuse=True)
    assert "other seeds" in capsys.readouterr().err
    assert {p for _, p in fake} == {("MPDM", "RBTS", "lookahead", "hungarian", "RTAW", "RTAW+")}


def test_transfer_has_a_table_per_learned_policy(fake):
    text = pt.transfer([0, 1], workers=1)
    assert "| RTAW: trained on \\ evaluated on | A |" in text
    assert "| RTAW+: trained on \\ evaluated on | A |" in text
    assert "- RTAW+ vs MPDM, pooled: own layout +12.0%" in text
    assert ("('C', 'D')", ("RTAW", "RTAW+")) in fake


def test_a_missing_checkpoint_is_skipped_with_one_warning(monkeypatch, capsys):
    def missing(name):
        raise ConfigError(f"pretrained policy {name!r} is not shipped")

    monkeypatch.setattr(pt, "pretrained_path", missing)
    pt.learned_entry.cache_clear()
    try:
        job = {"pretrained": "A_astar_m10", "hindsight": False}
        assert pt.wanted(job) == ["MPDM", "RBTS", "lookahead", "hungarian"]
        assert pt.wanted(job) == ["MPDM", "RBTS", "lookahead", "hungarian"]
    finally:
        pt.learned_entry.cache_clear()
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 2
    assert all(line.startswith("warning: RTAW") for line in err)


def test_table1_uses_both_networks_at_three_times_the_budget(fake, monkeypatch):
    """Table I's RTAW and RTAW+ columns are each row's 1,228,800-frame policies."""
    loaded = set()

    def entry(scenario, label):
        loaded.add((label, scenario + pt.LEARNED[label]))
        return scenario + pt.LEARNED[label]

    monkeypatch.setattr(pt, "learned_entry", entry)
    assert pt.main(["table1", "--seeds", "2"]) == 0
    assert ("RTAW+", "C_astar_m100_long_plus") in loaded
    assert ("RTAW", "C_astar_m100_long") in loaded
    assert len(loaded) == 24
    assert all("_long" in name for _, name in loaded)


def test_budget_gain_pairs_each_row_with_its_bases(fake, monkeypatch, capsys):
    """experiments/budget_gain.py: both networks' bases on every row and mode, paired per
    seed with Table I's stored columns."""
    monkeypatch.setitem(sys.modules, "paper_tables", pt)  # budget_gain's, with the fakes
    bg = load_experiment("budget_gain")
    seeds = list(range(20))
    rules = fake_ttd(list(MEANS), seeds)
    rows = {f"{label}, M={m}": rules for label, *_ in pt.ROWS for m in (10, 100)}
    pt.DATA.mkdir()
    for mode in ("paper", "drain"):
        (pt.DATA / f"table1_{mode}.json").write_text(json.dumps({"seeds": seeds, "rows": rows}))
    asked = []

    def evaluated(jobs, workers):  # RTAW+'s base 2% worse than Table I's, RTAW's 1% better
        for job in jobs:
            asked.append((job["policies"], job["pretrained"]))
            plus = [t / 0.98 for t in rules["RTAW+"]]
            yield {
                "key": job["key"],
                "ttd": {"RTAW+": plus, "RTAW": [t * 0.99 for t in rules["RTAW"]]},
            }

    monkeypatch.setattr(pt, "evaluated", evaluated)
    monkeypatch.setattr("sys.argv", ["budget_gain.py"])
    assert bg.main() == 0
    # The bases are the 409,600-frame entries, not Table I's "_long" ones.
    assert (("RTAW", "RTAW+"), "C_astar_m100") in asked
    assert len(asked) == 24
    out = capsys.readouterr().out
    assert out.count("| A* layout C, M=100 |") == 2  # paper and drain
    assert "- RTAW+ 3x vs 1x: +2.0% [+2.0, +2.0]* (n=480)" in out
    assert "- RTAW 3x vs 1x: -1.0% [-1.0, -1.0]* (n=480)" in out
    saved = json.loads((pt.DATA / "budget_gain.json").read_text())
    assert len(saved["rows"]) == 24
    assert set(saved["rows"]["drain|A* layout C, M=100"]) == {"RTAW", "RTAW+"}

    def fail(jobs, workers):
        raise AssertionError("--reuse evaluated again")
        yield

    monkeypatch.setattr(pt, "evaluated", fail)
    monkeypatch.setattr("sys.argv", ["budget_gain.py", "--reuse"])
    assert bg.main() == 0
    assert "(n=480)" in capsys.readouterr().out
