"""No training episode is an evaluation (0-19) or selection (1000-1999) episode, on any
route: the batched collectors, the interop route, Ray's actors and unseeded env resets.
(BenchMARL's route: ``tests/integrations/benchmarl_cases.py``.)

Every episode of every simulator goes through ``WarehouseSim.reset(seed)``, so the tests
record the seeds there while a real collector (or env) plays episodes of a tiny
scenario with the run's ``seed=0``, the value that used to replay evaluation seed 0.
"""

from __future__ import annotations

import numpy as np
import pytest
import torch

from rtaw_marl import warehouse_v1
from rtaw_marl.envs.gymnasium import WarehouseEnv
from rtaw_marl.envs.torchrl_wrapper import WarehouseWrapper
from rtaw_marl.sim.core import WarehouseSim
from rtaw_marl.sim.inputs import (
    RESERVED_SEEDS,
    TRAINING_SEED_END,
    draw_training_seed,
    training_seed,
)
from rtaw_marl.training import collectors
from rtaw_marl.training.checkpoints import Progress
from rtaw_marl.training.interop import BATCHED_KEYS, INTEROP_KEYS
from rtaw_marl.training.ppo import build_learner

pytestmark = pytest.mark.unit

#: A tiny scenario whose episodes end every few frames, so a batch plays many of them.
TINY = ["scenario=poc", "seed=0", "collector.envs_per_worker=2", "algo.frames_per_batch=64"]


@pytest.fixture
def episode_seeds(monkeypatch: pytest.MonkeyPatch) -> list[int]:
    """The seed of every episode any simulator of this process starts."""
    seen: list[int] = []
    reset = WarehouseSim.reset

    def recording(self: WarehouseSim, seed: int | None = None) -> None:
        seen.append(int(seed))
        reset(self, seed)

    monkeypatch.setattr(WarehouseSim, "reset", recording)
    return seen


def assert_training_seeds(seeds: list[int], at_least: int) -> None:
    assert len(seeds) >= at_least, seeds
    reserved = [s for s in seeds if s < RESERVED_SEEDS]
    assert not reserved, f"training episodes replayed reserved seeds {reserved}"


def test_training_seeds_avoid_the_reserved_range() -> None:
    mapped = [training_seed(s) for s in range(3 * RESERVED_SEEDS)]
    assert min(mapped) == RESERVED_SEEDS
    assert len(set(mapped)) == len(mapped)
    assert training_seed(TRAINING_SEED_END - RESERVED_SEEDS) == RESERVED_SEEDS
    drawn = [draw_training_seed(np.random.default_rng(s)) for s in range(2000)]
    assert min(drawn) >= RESERVED_SEEDS
    assert max(drawn) < TRAINING_SEED_END


def collect(cfg, batches: int = 3) -> None:
    spec = cfg.sim_spec()
    keys = INTEROP_KEYS if cfg.interop else BATCHED_KEYS
    learner = build_learner(cfg, keys, torch.device("cpu"))
    collection = collectors.build_collector(
        cfg, spec, learner.loss.actor_network, torch.device("cpu"), Progress()
    )
    try:
        for i, _ in enumerate(collection.collector):
            if i + 1 == batches:
                break
    finally:
        collection.shutdown()


@pytest.mark.parametrize("model", ["rtaw", "rtaw_plus"])
def test_batched_route(train_cfg, episode_seeds: list[int], model: str) -> None:
    collect(train_cfg([*TINY, f"model={model}"]))
    # 3 batches of 64 frames, 5-task episodes on 2 simulators: dozens of episodes.
    assert_training_seeds(episode_seeds, at_least=20)


def test_interop_route(train_cfg, episode_seeds: list[int]) -> None:
    collect(train_cfg([*TINY, "interop=true"]))
    assert_training_seeds(episode_seeds, at_least=20)


def test_ray_route_seeds_its_actors_the_same_way(
    train_cfg, episode_seeds: list[int], monkeypatch: pytest.MonkeyPatch
) -> None:
    """Ray's actors get the same env constructors and ``set_seed`` calls; the cluster is
    replaced by one in-process ``ActorCollector`` (Ray's own run: ``test_ray.py``)."""

    class InProcess:
        def __init__(self, cfg, actors: int) -> None:
            assert actors == 1

        def collector(self, make_env, policy, kwargs):
            return collectors.ActorCollector(
                make_env[0], policy, auto_register_policy_transforms=False, **kwargs
            )

        def close(self) -> None:
            pass

    monkeypatch.setattr(collectors, "RayCluster", InProcess)
    collect(train_cfg([*TINY, "collector=ray", "collector.workers=1"]))
    assert_training_seeds(episode_seeds, at_least=20)


def test_unseeded_env_resets(episode_seeds: list[int]) -> None:
    kw = {
        "layout": {"name": "open", "width": 8, "height": 8},
        "navigator": "direct",
        "tasks": "random",
    }
    aec = warehouse_v1.env(num_robots=2, num_tasks=4, **kw)
    aec.reset(seed=0)  # an explicit seed is the caller's: evaluation seed 0 stays playable
    for _ in range(50):
        aec.reset()
    single = WarehouseEnv(num_robots=2, num_tasks=4, **kw)
    single.reset(seed=1)
    for _ in range(50):
        single.reset()
    assert episode_seeds[0] == 0
    assert episode_seeds[51] == 1
    assert_training_seeds(episode_seeds[1:51] + episode_seeds[52:], at_least=100)
    assert aec.unwrapped.episode_seed == episode_seeds[50]


def test_training_wrapper_maps_its_seeds(episode_seeds: list[int]) -> None:
    kw = {
        "layout": {"name": "open", "width": 8, "height": 8},
        "navigator": "direct",
        "tasks": "random",
    }
    plain = WarehouseWrapper(warehouse_v1.env(num_robots=2, num_tasks=4, **kw), seed=0)
    trained = WarehouseWrapper(
        warehouse_v1.env(num_robots=2, num_tasks=4, **kw), seed=0, training=True
    )
    assert plain._raw.episode_seed == 0  # a user's wrapper plays the seed it is given
    assert trained._raw.episode_seed == training_seed(0)
    trained.set_seed(5)
    assert trained._raw.episode_seed == training_seed(5)
