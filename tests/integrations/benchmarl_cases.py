"""The BenchMARL task ``rtaw/warehouse``: its config, specs, transforms, and BenchMARL's
MAPPO training on it for a few iterations (skipped without benchmarl)."""

from __future__ import annotations

import dataclasses
import re
from pathlib import Path

import pytest
import yaml

pytestmark = pytest.mark.integration

bm = pytest.importorskip("rtaw_marl.integrations.benchmarl", exc_type=ImportError)
pytest.importorskip("benchmarl")

import torch  # noqa: E402
from benchmarl.algorithms import MappoConfig  # noqa: E402
from benchmarl.experiment import Experiment, ExperimentConfig  # noqa: E402
from benchmarl.models.mlp import MlpConfig  # noqa: E402
from omegaconf.errors import ConfigKeyError, ValidationError  # noqa: E402

M, N, TASKS = 3, 4, 12
SMALL = {
    "layout": {"name": "open", "width": 12, "height": 12},
    "navigator": "direct",
    "tasks": "random",
    "num_robots": M,
    "num_tasks": TASKS,
    "queue_len": N,
}


def small_task(**overrides):
    return bm.WarehouseTask.WAREHOUSE.get_task(bm.load_task_config(**{**SMALL, **overrides}))


def first_valid(td):
    """The first non-empty slot of every row (the acting row's is the env's real mask)."""
    td.set(("agents", "action"), td.get(("agents", "action_mask")).int().argmax(-1))
    return td


def test_yaml_and_schema_agree() -> None:
    raw = yaml.safe_load(bm.CONFIG_PATH.read_text())
    assert raw.pop("defaults") == ["rtaw_warehouse_config", "_self_"]
    assert set(raw) == {f.name for f in dataclasses.fields(bm.TaskConfig)}
    assert bm.load_task_config() == raw
    assert bm.WarehouseTask.WAREHOUSE.get_task().config == raw


def test_config_errors_are_caught() -> None:
    with pytest.raises(ConfigKeyError):
        bm.load_task_config(num_robot=3)
    with pytest.raises(ValidationError):
        bm.load_task_config(num_robots="many")


def test_training_episodes_are_never_evaluation_or_selection_episodes() -> None:
    """BenchMARL seeds its envs with the experiment's seed (0 by default): the task maps
    it, and every later episode, outside the reserved seeds 0-1999."""
    from rtaw_marl.sim.inputs import RESERVED_SEEDS, training_seed

    env = small_task().get_env_fun(num_envs=1, continuous_actions=False, seed=0, device="cpu")()
    seeds = [env._raw.episode_seed]
    env.set_seed(1000)
    seeds.append(env._raw.episode_seed)
    for _ in range(20):
        env.rollout(TASKS + 1, policy=first_valid, break_when_any_done=False)
        seeds.append(env._raw.episode_seed)
    assert seeds[:2] == [training_seed(0), training_seed(1000)]
    assert len(set(seeds)) == len(seeds), seeds
    assert min(seeds) >= RESERVED_SEEDS, seeds


def test_specs_follow_the_env() -> None:
    task = small_task()
    env = task.get_env_fun(num_envs=1, continuous_actions=False, seed=0, device="cpu")()
    robots = [f"robot_{i}" for i in range(M)]
    assert task.group_map(env) == {"agents": robots}
    assert task.observation_spec(env)["agents", "observation", "observation"].shape == (
        M,
        46 * N + 3,
    )
    assert list(task.action_mask_spec(env)["agents"].keys()) == ["action_mask"]
    assert task.action_mask_spec(env)["agents", "action_mask"].shape == (M, N)
    assert task.state_spec(env)["state"].shape == (3 * M + 7 * N,)
    assert "ttd" in task.info_spec(env)["agents", "info"].keys()  # noqa: SIM118
    assert task.action_spec(env)["agents", "action"].space.n == N
    assert task.max_steps(env) == TASKS
    assert not task.has_render(env)
    assert task.supports_discrete_actions()
    assert not task.supports_continuous_actions()
    full = small_task(observation="full")
    env = full.get_env_fun(num_envs=1, continuous_actions=False, seed=0, device="cpu")()
    assert full.observation_spec(env)["agents", "observation", "observation"].shape[-1] == (
        3 * M + 46 * N + 3
    )


def test_rows_of_idle_robots_and_team_reward() -> None:
    from torchrl.envs import TransformedEnv

    task = small_task(reward_scale=0.5)
    base = task.get_env_fun(num_envs=1, continuous_actions=False, seed=0, device="cpu")()
    env = TransformedEnv(base, task.get_env_transforms(base)[0])
    td = env.reset()
    rollout = env.rollout(TASKS, first_valid, tensordict=td, auto_reset=False)
    assert rollout.shape == (TASKS,)
    assert bool(rollout[-1]["next", "done"])
    acting = rollout["agents", "mask"]
    assert (acting.sum(-1) == 1).all()
    mask = rollout["agents", "action_mask"]
    assert (mask[~acting].sum(-1) == 1).all()
    assert mask[~acting][:, 0].all()
    reward = rollout["next", "agents", "reward"].squeeze(-1)
    assert (reward == reward[:, :1]).all()
    assert (reward <= 0).all()
    assert (reward < 0).any()
    # The same episode without the transform: the actor's reward alone, unscaled.
    raw = base.rollout(TASKS, first_valid, tensordict=base.reset(seed=7), auto_reset=False)
    again = env.rollout(TASKS, first_valid, tensordict=env.reset(seed=7), auto_reset=False)
    actor = raw["next", "agents", "reward"].squeeze(-1).sum(-1)
    assert torch.equal(again["next", "agents", "reward"][:, 0, 0], 0.5 * actor)


def test_mappo_trains_a_few_iterations(tmp_path) -> None:
    cfg = ExperimentConfig.get_from_yaml()
    cfg.max_n_iters, cfg.max_n_frames = 2, None
    cfg.on_policy_collected_frames_per_batch = 48
    cfg.on_policy_n_envs_per_worker = 2
    cfg.on_policy_minibatch_size = 24
    cfg.on_policy_n_minibatch_iters = 2
    cfg.lr = 1e-3
    cfg.evaluation, cfg.render, cfg.create_json = False, False, False
    cfg.loggers = []
    cfg.checkpoint_interval, cfg.checkpoint_at_end = 0, False
    cfg.save_folder = str(tmp_path)
    model = MlpConfig(num_cells=[16], layer_class=torch.nn.Linear, activation_class=torch.nn.Tanh)
    experiment = Experiment(
        task=small_task(),
        algorithm_config=MappoConfig.get_from_yaml(),
        model_config=model,
        critic_model_config=model,
        seed=0,
        config=cfg,
    )
    before = {k: v.clone() for k, v in experiment.policy.state_dict().items()}
    experiment.run()
    assert experiment.total_frames == 96
    after = experiment.policy.state_dict()
    assert any(not torch.equal(before[k], after[k]) for k in before)


def test_docs_snippet_runs(tmp_path, monkeypatch, capsys) -> None:
    page = Path(__file__).resolve().parents[2] / "docs" / "benchmarl.md"
    (code,) = re.findall(r"```python\n(.*?)```", page.read_text(), re.S)
    monkeypatch.chdir(tmp_path)
    exec(compile(code, str(page), "exec"), {"__name__": "snippet"})
    assert capsys.readouterr().out.split()[-1] == "400"
