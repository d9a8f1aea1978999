"""evaluate(): per-seed metrics, and the fleet's counters with collision-aware navigators."""

from __future__ import annotations

import importlib

import pytest

from rtaw_marl.evaluation import evaluate
from rtaw_marl.evaluation.evaluate import TimeEstimate, duration, warm_up
from rtaw_marl.policies import make_baseline
from rtaw_marl.sim.builder import SimSpec, build_sim

pytestmark = pytest.mark.unit

ENV = {"num_robots": 10, "num_tasks": 30, "noise_mean": 0.0, "noise_var": 0.0}


@pytest.mark.parametrize("navigator", ["astar", "sipp", "cbs"])
def test_fleet_counters_only_with_collision_aware_navigators(navigator: str) -> None:
    sim = build_sim(SimSpec.of(ENV, {"name": "preset", "preset": "A"}, navigator, "designated"))
    res = evaluate(sim, {"mpdm": make_baseline("mpdm")}, [0, 1])["mpdm"]
    assert len(res["ttd"]) == len(res["wall_time_s"]) == 2
    counters = {"planning_calls", "evacuations", "cbs_fallbacks"}
    if navigator == "astar":
        assert not counters & set(res)
    else:
        assert counters <= set(res)
        # Every decision plans at least once.
        assert min(res["planning_calls"]) >= ENV["num_tasks"]


def test_waiting_makes_ttd_no_shorter_than_astar() -> None:
    """Waits only add: with every decision at t = 0 the choices coincide, so each task's
    executed TTD (SIPP, CBS) is at least its A* distance.

    Over a longer episode the sums can differ either way: different completion times
    lead to different decisions.
    """
    sims = {
        nav: build_sim(SimSpec.of({**ENV, "num_tasks": 10}, {"name": "preset", "preset": "C"}, nav,
                       "designated"))
        for nav in ("astar", "sipp", "cbs")
    }  # fmt: skip
    ttd = {}
    for nav, sim in sims.items():
        sim.reset(4)
        policy = make_baseline("mpdm")
        policy.reset(4)
        while not sim.done:
            sim.step(policy.act_sim(sim))
        ttd[nav] = sim.task_ttd[:10]
    assert (ttd["sipp"] >= ttd["astar"]).all()
    assert (ttd["cbs"] >= ttd["astar"]).all()


class _Order:
    """A policy that records which (policy, seed) episodes it plays."""

    def __init__(self, name: str, log: list[tuple[str, int]]) -> None:
        self.name, self.log, self.inner = name, log, make_baseline("mpdm")

    def reset(self, seed: int | None = None) -> None:
        self.log.append((self.name, int(seed)))
        self.inner.reset(seed)

    def act_sim(self, sim) -> int:
        return self.inner.act_sim(sim)


def test_episodes_run_seed_by_seed_and_on_seed_counts_the_seeds_run(tmp_path) -> None:
    """Every policy plays a seed before the next seed starts, so the first seeds time
    every policy; ``on_seed`` counts only seeds with episodes to run (not replayed)."""
    from rtaw_marl.evaluation.journal import EpisodeJournal

    sim = build_sim(SimSpec.of({**ENV, "num_tasks": 5}))
    log: list[tuple[str, int]] = []
    policies = {n: _Order(n, log) for n in ("a", "b")}
    journal = EpisodeJournal(tmp_path / "j.jsonl", {}, resume=False)
    # No warm-up: it would log resets of its own (tested below).
    first = evaluate(sim, policies, [3, 1], journal=journal, warm_up_decisions=0)
    assert log == [("a", 3), ("b", 3), ("a", 1), ("b", 1)]
    journal.close()
    journal = EpisodeJournal(tmp_path / "j.jsonl", {}, resume=True)
    log.clear()
    calls: list[tuple[int, int]] = []

    def on_seed(done: int, total: int) -> None:
        calls.append((done, total))

    again = evaluate(
        sim,
        policies,
        [3, 1, 2, 0],
        journal=journal,
        on_seed=lambda *c: calls.append(c),
        warm_up_decisions=0,
    )
    assert log == [("a", 2), ("b", 2), ("a", 0), ("b", 0)]
    assert calls == [(1, 2), (2, 2)]
    assert again["a"]["ttd"][:2] == first["a"]["ttd"]


class _Clock:
    """Seconds that advance by ``step`` on every reading."""

    def __init__(self, step: float) -> None:
        self.now, self.step = -step, step

    def __call__(self) -> float:
        self.now += self.step
        return self.now


def test_time_estimate_announces_a_long_run_once_from_the_seeds_after_the_first() -> None:
    """30 s per seed after a 5 s first seed (warm-up, left out of the rate): one line,
    once; the bar's postfix follows every seed."""
    lines: list[str] = []
    shown: list[str] = []
    readings = iter([0.0, 5.0, 35.0, 65.0, 95.0])
    estimate = TimeEstimate(lines.append, shown.append, clock=lambda: next(readings))
    for done in range(1, 5):
        estimate(done, 10)
    assert lines == [
        "estimated time: 4.6 min in all, 4.0 min left (30 s per seed, 10 seeds to run)"
    ]
    assert shown == ["~4.0 min left", "~3.5 min left", "~3.0 min left"]


def test_time_estimate_from_one_long_first_seed() -> None:
    """A first seed past the warm-up bound is long enough to estimate from at once."""
    lines: list[str] = []
    estimate = TimeEstimate(lines.append, clock=iter([0.0, 90.0]).__next__)
    estimate(1, 10)
    assert lines == [
        "estimated time: 15.0 min in all, 13.5 min left (90 s per seed, 10 seeds to run)"
    ]


def test_time_estimate_is_silent_for_a_short_run() -> None:
    """A run estimated at under a minute prints nothing; the postfix still shows."""
    lines: list[str] = []
    shown: list[str] = []
    estimate = TimeEstimate(lines.append, shown.append, clock=_Clock(1.0))
    for done in range(1, 6):
        estimate(done, 5)
    assert lines == []
    assert shown == ["~3 s left", "~2 s left", "~1 s left", "~0 s left"]


@pytest.mark.parametrize(
    ("seconds", "text"),
    [(0.4, "0 s"), (89, "89 s"), (90, "1.5 min"), (5399, "90.0 min"), (5400, "1.5 h"),
     (48 * 3600, "2.0 days")],
)  # fmt: skip
def test_duration(seconds: float, text: str) -> None:
    assert duration(seconds) == text


class _FakeTime:
    """A ``time`` module whose clock moves only when a policy says so."""

    def __init__(self) -> None:
        self.now = 0.0

    def perf_counter(self) -> float:
        return self.now

    def monotonic(self) -> float:
        return self.now


class _Compiling:
    """A policy whose decisions cost 1 fake second each, plus a one-time 100 s the first
    time any policy decides (like numba kernels shared by every policy)."""

    def __init__(self, clock: _FakeTime, compiled: list[bool]) -> None:
        self.clock, self.compiled, self.inner = clock, compiled, make_baseline("mpdm")

    def reset(self, seed: int | None = None) -> None:
        self.inner.reset(seed)

    def act_sim(self, sim) -> int:
        if not self.compiled:
            self.compiled.append(True)
            self.clock.now += 100.0
        self.clock.now += 1.0
        return self.inner.act_sim(sim)


def _timed(monkeypatch, order: list[str], **kwargs) -> tuple[dict, int]:
    """``evaluate`` of policies in ``order`` under a fake clock; the results and the
    decisions reported to the progress callback."""
    # The package's ``evaluate`` attribute is the function: the module by its name.
    module = importlib.import_module("rtaw_marl.evaluation.evaluate")
    clock, compiled = _FakeTime(), []
    monkeypatch.setattr(module, "time", clock)
    sim = build_sim(SimSpec.of({**ENV, "num_tasks": 20}))
    counted: list[int] = []
    policies = {name: _Compiling(clock, compiled) for name in order}
    results = evaluate(sim, policies, [0, 1], on_decisions=counted.append, **kwargs)
    return results, sum(counted)


def test_s_per_episode_excludes_one_time_compilation_whatever_the_order(monkeypatch) -> None:
    """Each policy warms up before its first timed episode: every episode's wall time is
    its decisions' cost, in either order; the warm-up's decisions are not counted as
    progress and do not change the outcomes."""
    by_order = {}
    for order in (["a", "b"], ["b", "a"]):
        results, counted = _timed(monkeypatch, order)
        for metrics in results.values():
            assert metrics["wall_time_s"] == [float(d) for d in metrics["decisions"]]
        assert counted == sum(sum(m["decisions"]) for m in results.values())
        by_order[tuple(order)] = results
    assert by_order[("a", "b")]["a"]["ttd"] == by_order[("b", "a")]["a"]["ttd"]
    cold, _ = _timed(monkeypatch, ["a", "b"], warm_up_decisions=0)
    assert cold["a"]["ttd"] == by_order[("a", "b")]["a"]["ttd"]
    # Without the warm-up the first policy's first episode pays the 100 s.
    assert cold["a"]["wall_time_s"][0] == cold["a"]["decisions"][0] + 100.0
    assert cold["b"]["wall_time_s"][0] == cold["b"]["decisions"][0]


def test_warm_up_plays_at_most_its_decisions_and_leaves_the_episode_unchanged() -> None:
    sim = build_sim(SimSpec.of({**ENV, "num_tasks": 20}))
    policy = make_baseline("mpdm")
    assert warm_up(sim, policy, 0, 5) == 5
    assert warm_up(sim, policy, 0, 10_000) == sim.metrics().decisions
    warmed = evaluate(sim, {"mpdm": policy}, [0])["mpdm"]["ttd"]
    cold = evaluate(sim, {"mpdm": policy}, [0], warm_up_decisions=0)["mpdm"]["ttd"]
    assert warmed == cold
