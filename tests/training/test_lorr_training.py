"""Training on a LoRR problem with PIBT execution: the batched env runs horizon episodes
(which end after different numbers of decisions) in lockstep, and rtaw-train learns."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import torch

from rtaw_marl.envs.torchrl import BatchedWarehouseEnv
from rtaw_marl.evaluation import evaluate
from rtaw_marl.policies.network import load_policy
from rtaw_marl.scenarios import lorr_scenario
from rtaw_marl.sim.builder import build_sim
from rtaw_marl.training.ppo import train
from tests.cli.test_eval_cli import _tiny_lorr_problem

pytestmark = pytest.mark.integration


def test_batched_env_runs_horizon_episodes_in_lockstep(tmp_path: Path) -> None:
    """Two simulators whose horizon episodes take different numbers of decisions: the
    ended one ignores its actions, and each ends as a lone simulator does."""
    spec = lorr_scenario(_tiny_lorr_problem(tmp_path), horizon=40).spec()
    env = BatchedWarehouseEnv(spec, num_envs=2, seed=0)
    td = env.reset_to([3, 4])
    ends = [None, None]
    steps = 0
    while not bool(td["done"].all()):
        td["action"] = td["action_mask"].to(torch.int64).argmax(-1)
        td = env.step(td)["next"]
        steps += 1
        for i in range(2):
            if ends[i] is None and bool(td["done"][i]):
                ends[i] = steps
    for i, seed in enumerate([3, 4]):
        lone = build_sim(spec)
        lone.reset(seed)
        while not lone.done:
            lone.step(int(np.flatnonzero(lone.queue_mask)[0]))
        assert lone.metrics() == env.sims[i].metrics()
        assert ends[i] == lone.decisions
    assert env.sims[0].metrics().tasks_finished > 0


def test_rtaw_train_on_a_lorr_problem_with_pibt(train_cfg, tmp_path: Path) -> None:
    """A short RTAW+ run on a LoRR problem: checkpoints are written, and the saved policy
    evaluates on the same scenario with every PIBT episode passing the checker."""
    problem = _tiny_lorr_problem(tmp_path)
    overrides = ["scenario=lorr", f"tasks.problem={problem}", "sim.horizon=60",
                 "frames=1024", "selection.every_frames=512", "collector.envs_per_worker=4",
                 "model=rtaw_plus"]  # fmt: skip
    result = train(train_cfg(overrides), tmp_path / "run")
    assert result.frames == 1024
    assert [row["frames"] for row in result.history] == [0, 512, 1024]
    assert all(np.isfinite(row["ttd"]) for row in result.history)
    policy = load_policy(str(result.last_checkpoint))
    sim = build_sim(lorr_scenario(problem, horizon=60).spec())
    assert sim.executor.name == "pibt"
    results = evaluate(sim, {"rtaw": policy}, [0, 1])  # validates each schedule
    assert min(results["rtaw"]["tasks_finished"]) > 0


def test_rtaw_train_on_candidates_of_a_lorr_window(train_cfg, tmp_path: Path) -> None:
    """``candidates=K``: the run trains and selects on each decision's K nearest tasks
    (batches of width K, not the window's), and the checkpoint evaluates with
    ``candidates=K`` (the same slots, NetworkPolicy's)."""
    problem = _tiny_lorr_problem(tmp_path)
    overrides = ["scenario=lorr", f"tasks.problem={problem}", "sim.horizon=60",
                 "frames=1024", "collector.envs_per_worker=4",
                 "model=rtaw_plus", "candidates=2", "sim.reward=pair_cost",
                 "selection.metric=tasks_finished", "selection.every_frames=512"]  # fmt: skip
    cfg = train_cfg(overrides)
    assert cfg.sim.queue_len > 2
    result = train(cfg, tmp_path / "run")
    assert result.frames == 1024
    assert all(np.isfinite(row["ttd"]) for row in result.history)
    # Selected on tasks finished: the best row has the most (the earliest on ties).
    rows = result.history
    assert all(row["score"] == -row["tasks_finished"] for row in rows)
    best = torch.load(result.best_checkpoint, weights_only=False)
    assert best["eval"]["tasks_finished"] == max(row["tasks_finished"] for row in rows)
    assert result.best == best["eval"]
    # The bar to clear under LoRR's reassignment is the winner's rule, on every row.
    assert result.rule == "pair_greedy"
    assert all(row["pair_greedy_tasks_finished"] > 0 for row in rows)
    assert all("pair_greedy_ttd" in row and "lookahead_ttd" not in row for row in rows)
    assert "time/update_s" in result.timings
    assert best["eval"]["frames"] == min(
        r["frames"] for r in rows if r["tasks_finished"] == best["eval"]["tasks_finished"]
    )
    policy = load_policy(str(result.last_checkpoint), candidates=2)
    sim = build_sim(lorr_scenario(problem, horizon=60).spec())
    results = evaluate(sim, {"rtaw": policy}, [0])
    assert min(results["rtaw"]["tasks_finished"]) > 0


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["candidates=0"], "candidates must be >= 1"),
        (["candidates=4", "imitation.teacher=lookahead"], "does not work with imitation"),
        (["candidates=4", "interop=true"], "does not work with interop"),
        (["selection.metric=tasks"], "selection.metric must be one of ttd, tasks_finished"),
    ],
)
def test_bad_candidates_or_metric_are_one_line(
    extra: list[str], message: str, cli, tmp_path
) -> None:
    result = cli(
        "train", "scenario=poc", "frames=1024", "algo=ppo_paper", f"output_dir={tmp_path}",
        "progress=false", *extra,
    )  # fmt: skip
    assert result.code == 2
    assert message in result.err
    assert "Traceback" not in result.err + result.out


def test_rtaw_train_ends_with_the_bar_to_clear(cli, tmp_path: Path) -> None:
    """Selected on tasks finished under LoRR's reassignment, the last lines name the
    checkpoint's count against MPDM and against the winner's rule."""
    problem = _tiny_lorr_problem(tmp_path)
    result = cli(
        "train", "scenario=lorr", f"tasks.problem={problem}", "sim.horizon=60", "frames=1024",
        "selection.every_frames=512", "algo=ppo_paper", "model=rtaw_plus",
        "candidates=2", "selection.metric=tasks_finished", "progress=false",
        f"output_dir={tmp_path / 'run'}",
    )  # fmt: skip
    assert result.code == 0, result.err
    line = next(ln for ln in result.out.splitlines() if ln.startswith("best greedy tasks"))
    assert "vs MPDM" in line
    assert ", pair_greedy " in line
