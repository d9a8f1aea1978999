"""Traffic-flow guidance for lifelong PIBT (``navigator.guidance``): guide paths on
contraflow costs, kept in step with the fleet, followed by PIBT."""

from __future__ import annotations

import numpy as np
import pytest

from rtaw_marl.errors import ConfigError
from rtaw_marl.evaluation.evaluate import run_episode
from rtaw_marl.policies import make_baseline
from rtaw_marl.sim.builder import SimSpec, build_sim
from rtaw_marl.sim.layout import open_grid
from rtaw_marl.sim.mapf import check_schedule
from rtaw_marl.sim.mapf._guidance import guide_advance, guide_plan
from rtaw_marl.sim.mapf._pibt import bfs_compact, compact_graph
from rtaw_marl.sim.options import navigator_option

pytestmark = pytest.mark.unit


class Guides:
    """Guide-path state of ``m`` robots on an open ``w x h`` grid, for the kernels."""

    def __init__(self, w: int, h: int, m: int) -> None:
        self.index, self.cells, self.nbr = compact_graph(open_grid(w, h).obstacles)
        c = len(self.cells)
        self.buf = np.empty(8 * c, dtype=np.int64)
        self.start = np.full(m, -1, dtype=np.int64)
        self.length = np.zeros(m, dtype=np.int64)
        self.at = np.zeros(m, dtype=np.int64)
        self.flow = np.zeros((c, 4), dtype=np.int32)
        self.fields = np.empty((m, c), dtype=np.int32)
        self.cursor, self.epoch = 0, 0
        self.scratch = (np.zeros(c), np.zeros(c, np.int64), np.full(c, -1, np.int64))
        self.heap = (np.empty(4 * c), np.empty(4 * c, np.int64))

    def cell(self, x: int, y: int) -> int:
        return int(self.index[y, x])

    def plan(self, robots, pos, goal, weight: float) -> None:
        for r in robots:
            bfs_compact(self.nbr, int(goal[r]), self.fields[r])
        robots = np.asarray(robots, dtype=np.int64)
        self.cursor, planned = guide_plan(
            robots, pos, goal, np.arange(len(pos)), self.fields, self.nbr, self.flow, weight,
            self.buf, self.cursor, self.start, self.length, self.at, *self.scratch,
            self.epoch, *self.heap,
        )  # fmt: skip
        assert planned == len(robots)
        self.epoch += len(robots)

    def path(self, r: int) -> list[tuple[int, int]]:
        s = self.start[r]
        return [tuple(self.cells[c]) for c in self.buf[s + self.at[r] : s + self.length[r]]]


def test_an_uncongested_guide_is_a_shortest_path_and_its_edges_are_the_flow() -> None:
    g = Guides(6, 3, 1)
    pos = np.array([g.cell(0, 1)], dtype=np.int64)
    goal = np.array([g.cell(5, 1)], dtype=np.int64)
    g.plan([0], pos, goal, weight=1.0)
    assert g.path(0) == [(x, 1) for x in range(6)]
    assert int(g.flow.sum()) == 5
    assert int(g.flow[g.cell(2, 1), 0]) == 1  # the edge (2, 1) -> (3, 1), +x


def test_a_guide_steps_aside_from_an_oncoming_stream() -> None:
    """Two robots planned head-on along one row: the second pays for the first's
    contraflow and takes a neighbouring row instead (one cell longer each way)."""
    g = Guides(8, 3, 2)
    pos = np.array([g.cell(0, 1), g.cell(7, 1)], dtype=np.int64)
    goal = np.array([g.cell(7, 1), g.cell(0, 1)], dtype=np.int64)
    g.plan([0], pos, goal, weight=1.0)
    g.plan([1], pos, goal, weight=1.0)
    first, second = g.path(0), g.path(1)
    assert len(first) == 8
    assert len(second) == 8 + 2
    middle = {c for c in second if c[0] not in (0, 7)}
    assert not middle & set(first)  # no shared cell between the ends
    g2 = Guides(8, 3, 2)
    g2.plan([0], pos, goal, weight=0.0)
    g2.plan([1], pos, goal, weight=0.0)
    assert len(g2.path(1)) == 8  # without guidance: the shortest path, head-on


def test_walking_a_guide_takes_its_edges_out_and_a_push_replans() -> None:
    g = Guides(6, 3, 1)
    pos = np.array([g.cell(0, 1)], dtype=np.int64)
    goal = np.array([g.cell(5, 1)], dtype=np.int64)
    g.plan([0], pos, goal, weight=1.0)
    need = np.zeros(1, dtype=bool)
    pos[0] = g.cell(1, 1)  # one step along
    guide_advance(pos, goal, g.buf, g.start, g.length, g.at, g.flow, g.nbr, need)
    assert not need[0]
    assert int(g.flow.sum()) == 4
    assert g.path(0)[0] == (1, 1)
    pos[0] = g.cell(1, 2)  # pushed off the path
    guide_advance(pos, goal, g.buf, g.start, g.length, g.at, g.flow, g.nbr, need)
    assert need[0]
    assert int(g.flow.sum()) == 0
    assert g.start[0] == -1
    g.plan([0], pos, goal, weight=1.0)
    for x in range(2, 6):  # walked to the goal: the path and its flow are gone
        pos[0] = g.cell(x, 2) if x < 5 else g.cell(5, 1)
        guide_advance(pos, goal, g.buf, g.start, g.length, g.at, g.flow, g.nbr, need)
    assert g.start[0] == -1
    assert int(g.flow.sum()) == 0


def lorr_random(turns: bool, guidance: float):
    from rtaw_marl.scenarios.lorr import lorr_scenario

    problem = "builtin:random_32_32_20_100.json"
    nav = {"name": "pibt", "turns": turns, "guidance": guidance}
    return build_sim(lorr_scenario(problem, horizon=300, navigator=nav).spec())


def test_guided_episodes_are_valid_deterministic_and_finish_more() -> None:
    """LoRR's random map, 100 robots, 300 timesteps, turning robots: valid schedules, the
    same tasks for the same seed, and more tasks finished with guidance than without."""
    guided = []
    for _ in range(2):
        sim = lorr_random(turns=True, guidance=1.0)
        guided.append(run_episode(sim, make_baseline("mpdm"), 0).tasks_finished)
        check_schedule(sim.layout, sim.schedule())
        stats = sim.executor.stats()
        assert stats["guide_paths"] > guided[-1]  # one per errand at least
    assert guided[0] == guided[1]
    plain = lorr_random(turns=True, guidance=0.0)
    assert guided[0] > run_episode(plain, make_baseline("mpdm"), 0).tasks_finished
    assert "guide_paths" not in plain.executor.stats()


@pytest.mark.parametrize("value", [-1.0, float("inf"), float("nan")])
def test_guidance_must_be_a_finite_non_negative_number(value: float) -> None:
    with pytest.raises(ConfigError, match=r"navigator\.guidance must be a number >= 0"):
        navigator_option({"name": "pibt", "guidance": value})


def test_spec_with_guidance_builds() -> None:
    spec = SimSpec.of({"num_robots": 5}, "shelves", {"name": "pibt", "guidance": 0.5}, "random")
    assert build_sim(spec).executor.guidance == 0.5


def test_the_guide_buffer_stays_bounded_over_a_long_episode() -> None:
    """Replanning appends paths; compaction keeps only what is left to walk, so the
    buffer does not grow with the episode (it doubled at every compaction once)."""
    sim = lorr_random(turns=True, guidance=1.0)
    sim.reset(0)
    rule = make_baseline("mpdm")
    ex = sim.executor
    sizes = []
    while not sim.done:
        sim.step(rule.act_sim(sim))
        sizes.append(len(ex.guides.buf))
    c, m = len(ex.cells), ex.num_robots
    assert max(sizes) == 8 * c + 64 * m  # never grown on this map
    written = ex.stats()["guide_paths"]
    assert written > 10 * m  # the paths written would have overflowed it many times
