"""Shared fixtures: running the command-line entry points in-process."""

from __future__ import annotations

import importlib
import sys
from dataclasses import dataclass

import pytest


@dataclass
class CliResult:
    """Exit status and captured output of one in-process CLI run."""

    code: int
    out: str
    err: str


@pytest.fixture
def cli(monkeypatch, tmp_path, capsys):
    """``cli("eval", "scenario=poc", ...)`` runs ``rtaw-eval`` in-process in ``tmp_path``.

    The same ``main`` as the console script (Hydra composition, one-line errors, exit
    status), without a new interpreter: a few hundred milliseconds instead of ten seconds.
    """

    def run(app: str, *args: str) -> CliResult:
        module = importlib.import_module(f"rtaw_marl.cli.{app}")
        monkeypatch.chdir(tmp_path)
        monkeypatch.setattr(sys, "argv", [f"rtaw-{app}", *args])
        capsys.readouterr()
        try:
            module.main()
            code = 0
        except SystemExit as exc:
            code = exc.code if isinstance(exc.code, int) else 1
        finally:
            _shut_down_joblib_workers()
        captured = capsys.readouterr()
        return CliResult(code, captured.out, captured.err)

    return run


def _shut_down_joblib_workers() -> None:
    """End the worker processes a ``hydra/launcher=joblib`` sweep leaves behind.

    Joblib keeps its loky workers for the next call in the same process, and they keep
    the working directory they started in: a later test's sweep (another ``tmp_path``)
    then wrote its jobs into the earlier test's folder, where the sweep's ``FAILED``
    markers were not found (``test_a_failed_job_does_not_stop_the_sweep[joblib]`` failed
    after ``test_multirun_sweep_trains_each_job_into_its_own_folder`` in one process). A
    console script is a fresh process: its workers start in its own directory.
    """
    loky = sys.modules.get("joblib.externals.loky.reusable_executor")
    executor = getattr(loky, "_executor", None)
    if executor is not None:
        executor.shutdown(wait=True)
