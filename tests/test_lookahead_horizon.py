"""experiments/lookahead_horizon.py: the horizon sweep evaluates on selection seeds, and
its H = 0 is MPDM itself."""

from __future__ import annotations

from experiment_scripts import load_experiment

lh = load_experiment("lookahead_horizon")


def test_the_sweep_never_touches_the_evaluation_seeds():
    assert min(lh.SEEDS) >= 1000
    assert len(lh.SEEDS) >= 20


def test_horizon_zero_is_mpdm_and_three_differs(monkeypatch):
    monkeypatch.setattr(lh, "SEEDS", [1000, 1001])
    env = {"num_robots": 5, "num_tasks": 40, "queue_len": 10, "episode_mode": "paper"}
    layout = {"name": "preset", "preset": "C", "width": 60, "height": 60}
    job = {"key": "tiny", "env": env, "layout": layout, "navigator": "astar", "horizons": [0, 3]}
    ttd = lh.evaluate_row(job)["ttd"]
    assert set(ttd) == {"MPDM", "H=0", "H=3"}
    assert ttd["H=0"] == ttd["MPDM"]
    assert ttd["H=3"] != ttd["MPDM"]
