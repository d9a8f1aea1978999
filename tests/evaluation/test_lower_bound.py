"""The assignment lower bound on TTD: valid for every policy, tight where it should be,
refused where it is not defined (``paper`` mode, streams that refill the same slot).

``test_lower_bound_exhaustive.py`` checks it against exhaustive search on tiny instances.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import linear_sum_assignment

from rtaw_marl.cli.eval import run
from rtaw_marl.config import compose
from rtaw_marl.errors import ConfigError
from rtaw_marl.evaluation import evaluate
from rtaw_marl.evaluation.lower_bound import ttd_lower_bound
from rtaw_marl.policies import make_baseline
from rtaw_marl.sim.builder import SimSpec, build_sim
from rtaw_marl.sim.core import WarehouseSim
from rtaw_marl.sim.tasks import FixedTasks
from tests.training.conftest import POC_LAYOUT, POC_SIM

pytestmark = pytest.mark.unit


@pytest.mark.parametrize(
    ("layout", "navigator", "tasks"),
    [
        ({"name": "open", "width": 15, "height": 12}, "direct", "random"),
        ({"name": "shelves", "width": 30, "height": 30}, "astar", "random"),
        ("shelves", "astar", "designated"),
    ],
)
@pytest.mark.parametrize("robots", [1, 4])
def test_bound_is_below_every_policy(layout, navigator: str, tasks: str, robots: int) -> None:
    sim = build_sim(
        SimSpec.of(
            {"num_robots": robots, "num_tasks": 40, "queue_len": 5}, layout, navigator, tasks
        )
    )
    policies = {name: make_baseline(name) for name in ("mpdm", "rbts", "random")}
    seeds = [0, 1, 2]
    results = evaluate(sim, policies, seeds)
    for i, seed in enumerate(seeds):
        bound = ttd_lower_bound(sim, seed)
        assert bound > 0
        for name in policies:
            assert bound <= results[name]["ttd"][i] + 1e-9, name


def test_bound_below_poc_optimum() -> None:
    sim = build_sim(
        SimSpec.of(
            POC_SIM,
            POC_LAYOUT,
            "direct",
            "poc",
        )
    )
    assert ttd_lower_bound(sim, 0) <= 17.936


def test_bound_is_tight_on_a_chain() -> None:
    """One robot, tasks laid end to end: every policy's TTD (2) equals the bound."""
    tasks = FixedTasks([[1, 0, 2, 0], [3, 0, 4, 0]])
    sim = build_sim(
        SimSpec.of(
            {"num_robots": 1, "num_tasks": 2, "queue_len": 1, "robot_starts": [[0, 0]]},
            {"name": "open", "width": 6, "height": 1},
            "astar",
            tasks,
        )
    )
    assert ttd_lower_bound(sim, 0) == 2.0
    sim.reset(0)
    assert -(sim.step(0) + sim.step(0)) == 2.0


def test_a_task_never_follows_itself() -> None:
    """A single task whose destination is next to its origin still pays the robot's travel."""
    tasks = FixedTasks([[5, 0, 4, 0]])
    sim = build_sim(
        SimSpec.of(
            {"num_robots": 1, "num_tasks": 1, "queue_len": 1, "robot_starts": [[0, 0]]},
            {"name": "open", "width": 6, "height": 1},
            "astar",
            tasks,
        )
    )
    assert ttd_lower_bound(sim, 0) == 5.0


def test_first_tasks_come_from_the_queue() -> None:
    """Robots free together act in id order, each on a task queued by then.

    Robot 0 (at x=0) must take task 0 (origin x=9, the only queued task) and robot 1 (at
    x=9) then takes task 1 (origin x=0): 18 whatever the policy. Ignoring the queue,
    each robot would take the task at its feet for 0.
    """
    tasks = FixedTasks([[9, 0, 8, 0], [0, 0, 1, 0]])
    sim = build_sim(
        SimSpec.of(
            {"num_robots": 2, "num_tasks": 2, "queue_len": 1, "robot_starts": [[0, 0], [9, 0]]},
            {"name": "open", "width": 10, "height": 1},
            "astar",
            tasks,
        )
    )
    assert untimed_assignment_bound(sim, 0) == 0.0
    assert ttd_lower_bound(sim, 0) == 18.0
    sim.reset(0)
    assert -(sim.step(0) + sim.step(0)) == 18.0


def test_a_task_at_the_robots_feet_takes_a_timestep_and_keeps_the_bound_valid() -> None:
    """A zero-length task at robot 0's feet (pickup = delivery, as in some LoRR files)
    takes one timestep, as in LoRR, not zero: robot 1 decides next at t=0 and travels
    5 cells to task 1; the bound stays at most the episode's TTD."""
    tasks = FixedTasks([[0, 0, 0, 0], [4, 0, 5, 0]])
    sim = build_sim(
        SimSpec.of(
            {
                "num_robots": 2,
                "num_tasks": 2,
                "queue_len": 1,
                "robot_starts": [[0, 0], [9, 0]],
                "noise_mean": 0,
                "noise_var": 0,
            },
            {"name": "open", "width": 10, "height": 1},
            "astar",
            tasks,
        )
    )
    sim.reset(0)
    assert sim.step(0) == 0.0
    assert (sim.robot, sim.time) == (1, 0.0)
    assert sim.robot_free_at[0] == 1.0
    assert sim.step(0) == -5.0
    assert sim.done
    assert ttd_lower_bound(sim, 0) <= 5.0


def untimed_assignment_bound(sim: WarehouseSim, seed: int) -> float:
    """The first version of the bound: ends to origins on the pre-drawn task list, with
    no timing (kept here to show why refilling streams must be refused)."""
    sim.reset(seed)
    tasks = sim.tasks[: sim.config.num_tasks]
    ends = np.concatenate([sim.robot_start_xy, tasks[:, 2:]])
    cost = sim.distance_model.distance_matrix(ends, tasks[:, :2])
    t = len(tasks)
    cost[sim.num_robots + np.arange(t), np.arange(t)] = np.inf
    rows, cols = linear_sum_assignment(cost)
    return float(cost[rows, cols].sum())


def test_same_slot_refill_is_refused() -> None:
    """Regression: with ``two_task`` the policy chooses which tasks are served.

    The pre-drawn list alternates the short task (0,0)->(3,3) and the long one
    (0,0)->(9,9), but a policy that always takes the short one serves only short tasks,
    and beats what an assignment on that list claimed to be a lower bound.
    """
    sim = build_sim(
        SimSpec.of(
            {"num_robots": 10, "num_tasks": 200, "queue_len": 2, "noise_mean": 0, "noise_var": 0},
            {"name": "open", "width": 10, "height": 10},
            "direct",
            "two_task",
        )
    )
    claimed = untimed_assignment_bound(sim, 0)
    sim.reset(0)
    while not sim.done:
        sim.step(int(np.argmin(np.where(sim.queue_mask, sim.queue_length, np.inf))))
    short = sim.metrics().ttd
    assert short < 0.6 * claimed  # about 865 against 1,628
    with pytest.raises(ConfigError, match=r"refill the same slot.*depends on the policy"):
        ttd_lower_bound(sim, 0)


def test_paper_mode_is_rejected() -> None:
    sim = build_sim(
        SimSpec.of(
            {"num_robots": 2, "num_tasks": 10, "episode_mode": "paper"}, "open", "direct", "random"
        )
    )
    with pytest.raises(ConfigError, match="drain"):
        ttd_lower_bound(sim, 0)


def test_scales_to_5000_tasks() -> None:
    sim = build_sim(
        SimSpec.of(
            {"num_robots": 1000, "num_tasks": 5000},
            {"name": "open", "width": 300, "height": 300},
            "direct",
            "random",
        )
    )
    bound = ttd_lower_bound(sim, 0)
    metrics = evaluate(sim, {"mpdm": make_baseline("mpdm")}, [0])
    assert 0 < bound <= metrics["mpdm"]["ttd"][0]


def test_rtaw_eval_reports_bound_and_gaps(tmp_path: Path) -> None:
    out = tmp_path / "r.json"
    cfg = compose(
        config_name="eval",
        overrides=[
            "sim.num_tasks=60",
            "policy=[mpdm,rbts]",
            "seeds=[0,1]",
            f"output={out}",
            "progress=false",
            "lower_bound=true",
        ],
    )
    run(cfg)
    data = json.loads(out.read_text())
    assert len(data["lower_bound"]) == 2
    for name in ("mpdm", "rbts"):
        gaps = data["policies"][name]["gap_pct"]
        assert all(g >= 0 for g in gaps)
        ttd, bound = data["policies"][name]["ttd"][0], data["lower_bound"][0]
        assert gaps[0] == pytest.approx(100 * (ttd - bound) / bound)
