"""The small executed episodes the viewer's tests show: layout A, SIPP, 12 robots."""

from __future__ import annotations

from rtaw_marl.evaluation.evaluate import run_episode
from rtaw_marl.policies import make_baseline
from rtaw_marl.sim.builder import SimSpec, build_sim
from rtaw_marl.sim.core import WarehouseSim
from rtaw_marl.sim.mapf.schedule import Schedule

#: 12 robots on layout A, 40 designated tasks, executed collision-free by SIPP.
SMALL_SIPP = SimSpec.of(
    {"num_robots": 12, "num_tasks": 40, "queue_len": 6},
    {"name": "A"},
    {"name": "sipp"},
    {"name": "designated"},
)


def played(
    policies: tuple[str, ...], seed: int
) -> tuple[WarehouseSim, dict[str, Schedule], dict[str, float]]:
    """Each rule's episode on ``seed``: the simulator, the schedules and the TTDs."""
    sim = build_sim(SMALL_SIPP)
    schedules, ttds = {}, {}
    for name in policies:
        ttds[name] = run_episode(sim, make_baseline(name), seed).ttd
        schedules[name] = sim.schedule()
    return sim, schedules, ttds
