"""What a learned policy does differently from MPDM and ``lookahead`` (docs/analysis.md).

Each learned policy plays its own greedy episodes on Table I's rows (``drain`` mode); at
every decision MPDM and ``lookahead`` are asked what they would choose in the same state
(:mod:`.decisions`), the decisions are pooled per policy and row (:mod:`.summary`) and
the page's tables and findings are written from them (:mod:`.page`). :mod:`.study`
makes it the ``analysis`` study (``python -m benchmarks.run analysis``); :func:`analyse` runs it
from Python with other rows, policies or checkpoint files.
"""

from __future__ import annotations

from benchmarks.analysis.decisions import Decision, Probe, play
from benchmarks.analysis.page import section
from benchmarks.analysis.study import ANALYSIS, analyse, analysis_study, render
from benchmarks.analysis.summary import Summary, summarise

__all__ = [
    "ANALYSIS",
    "Decision",
    "Probe",
    "Summary",
    "analyse",
    "analysis_study",
    "play",
    "render",
    "section",
    "summarise",
]
