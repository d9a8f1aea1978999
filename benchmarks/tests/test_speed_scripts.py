"""The speed benchmarks run: each script's quick mode, a few steps each (no timing asserted)."""

from __future__ import annotations

from pathlib import Path

import pytest

from benchmarks.scripts import bench_env, bench_wrapper

pytestmark = pytest.mark.integration


def test_bench_env_quick_smoke(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """``python -m benchmarks.scripts.bench_env --quick`` writes its markdown table."""
    out = tmp_path / "bench.md"
    report = bench_env.main(["--quick", "--output", str(out)])
    assert out.read_text() == report + "\n"
    assert "| benchmark | setting |" in report
    for name in ("sim+MPDM", "AEC first-valid", "AEC+MPDM(obs)", "episode MPDM", "episode RBTS"):
        assert f"| {name} |" in report
    assert report in capsys.readouterr().out


def test_bench_wrapper_runs(monkeypatch: pytest.MonkeyPatch) -> None:
    """``python -m benchmarks.scripts.bench_wrapper``: its rows for M = 10, a few steps each."""
    monkeypatch.setitem(bench_wrapper.STEPS, 10, 20)
    rows = bench_wrapper.run_all((10,), repeats=1, quick=True)
    warehouse = [
        ("warehouse", wrapper, observation, obs_format)
        for observation in ("compact", "full")
        for obs_format in ("dict", "flat")
        for wrapper in ("stock", "vectorised")
    ]
    assert [(r.env, r.wrapper, r.observation, r.obs_format) for r in rows] == [
        *warehouse,
        ("no-op", "stock", "compact", "flat"),
        ("no-op, no infos", "stock", "compact", "flat"),
    ]
    assert all(row.median > 0 for row in rows)
    report = bench_wrapper.render(rows, quick=True)
    assert "| warehouse | vectorised | compact | flat | 10 |" in report
    assert "x |" in report  # the speed-up column, vectorised over stock


def test_bench_policy_latency_times_the_search_beside_the_rules() -> None:
    """One row of ``bench_policy_latency``: every phase and policy has a median."""
    from benchmarks.scripts import bench_policy_latency

    res = bench_policy_latency.measure(10, 4, {"name": "preset", "preset": "C", "width": 30,
                                               "height": 30})  # fmt: skip
    assert set(res) == {"rtaw", "rtaw_plus", "mpdm", "lookahead", "search", "hungarian"}
    assert all(v > 0 for r in res.values() for v in r.values())
