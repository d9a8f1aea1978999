"""rtaw-train mechanics: resume, determinism, interop route, workers, checkpoints, CLI."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
import torch

from rtaw_marl.envs.torchrl import BatchedWarehouseEnv
from rtaw_marl.errors import ConfigError
from rtaw_marl.models.checkpoint import (
    FEATURES,
    build_networks,
    load_checkpoint,
    save_checkpoint,
)
from rtaw_marl.policies.labels import checkpoint_labels
from rtaw_marl.sim.builder import SimSpec
from rtaw_marl.training.evaluator import greedy_ttd
from rtaw_marl.training.ppo import train
from tests.training.conftest import POC_LAYOUT, POC_SIM

pytestmark = pytest.mark.integration

TINY = [
    "scenario=poc", "frames=1024", "selection.every_frames=512", "collector.envs_per_worker=4",
    "algo=ppo_paper",
]  # fmt: skip


def _actor_state(path: Path) -> dict[str, torch.Tensor]:
    return load_checkpoint(path)["model"]["actor"]


def test_resume_continues_frames_and_reloads_parameters(train_cfg, tmp_path: Path) -> None:
    first = train(train_cfg(TINY), tmp_path / "a")
    ckpt = load_checkpoint(first.last_checkpoint)
    assert ckpt["frames"] == 1024
    # Reloaded parameters reproduce the checkpoint's own evaluation exactly.
    actor, _ = build_networks(ckpt["model_config"])
    actor.load_state_dict(ckpt["model"]["actor"])
    seeds = list(ckpt["config"]["selection"]["seeds"])
    assert seeds == list(range(1000, 1010))  # selection seeds, never the evaluation seeds
    env = BatchedWarehouseEnv(SimSpec.of(**_poc_spec()), num_envs=len(seeds), seed=0)
    ttd = sum(greedy_ttd(actor, env, seeds)) / len(seeds)
    assert ttd == pytest.approx(ckpt["eval"]["ttd"])

    resumed = train(
        train_cfg(
            [
                *TINY[:1],
                "frames=2048",
                "selection.every_frames=512",
                "collector.envs_per_worker=4",
                f"resume={first.last_checkpoint}",
            ]
        ),
        tmp_path / "b",
    )
    after = load_checkpoint(resumed.last_checkpoint)
    assert after["frames"] == 2048
    assert after["iteration"] == ckpt["iteration"] + 2
    assert [row["frames"] for row in resumed.history][-2:] == [1536, 2048]
    assert after["optimizer"]["state"][0]["step"] > ckpt["optimizer"]["state"][0]["step"]


def _poc_spec() -> dict:
    return {"sim": POC_SIM, "layout": POC_LAYOUT, "navigator": "direct", "tasks": "poc"}


def test_same_seed_same_training_run(train_cfg, tmp_path: Path) -> None:
    a = train(train_cfg(TINY), tmp_path / "a")
    b = train(train_cfg(TINY), tmp_path / "b")
    sa, sb = _actor_state(a.last_checkpoint), _actor_state(b.last_checkpoint)
    assert all(torch.equal(sa[k], sb[k]) for k in sa)
    c = train(train_cfg([*TINY, "seed=1"]), tmp_path / "c")
    sc = _actor_state(c.last_checkpoint)
    assert not all(torch.equal(sa[k], sc[k]) for k in sa)


def test_same_seed_same_warm_started_run(train_cfg, tmp_path: Path) -> None:
    """Imitation included: the teacher's tie-breaking follows the run's seed (lookahead
    ties often on the default scenario, where every robot starts free at time 0)."""
    warm = ["model=rtaw_plus", "imitation.teacher=lookahead", "imitation.frames=1024",
            "imitation.rounds=2", "sim.num_tasks=60", "frames=512", "selection.every_frames=512",
            "algo.frames_per_batch=512", "algo.minibatch_size=128"]  # fmt: skip
    a = train(train_cfg(warm), tmp_path / "a")
    b = train(train_cfg(warm), tmp_path / "b")

    def figures(history: list[dict[str, float]]) -> list[dict[str, float]]:
        return [{k: v for k, v in row.items() if k != "wall_s"} for row in history]

    assert figures(a.history) == figures(b.history)
    sa, sb = _actor_state(a.last_checkpoint), _actor_state(b.last_checkpoint)
    assert all(torch.equal(sa[k], sb[k]) for k in sa)


def test_refuses_to_overwrite_a_run(train_cfg, tmp_path: Path) -> None:
    train(train_cfg(TINY), tmp_path)
    with pytest.raises(ConfigError, match="already holds a training run"):
        train(train_cfg(TINY), tmp_path)


def test_interop_route_trains_rtaw_plus(train_cfg, tmp_path: Path) -> None:
    """RTAW+ reads the relational entries of the PettingZoo observation through the
    wrapper's nested keys, and trains (with an imitation warm start)."""
    overrides = ["scenario=poc", "frames=512", "selection.every_frames=512", "interop=true",
                 "model=rtaw_plus", "imitation.teacher=lookahead",
                 "imitation.frames=64"]  # fmt: skip
    result = train(train_cfg(overrides), tmp_path)
    ckpt = load_checkpoint(result.last_checkpoint)
    assert ckpt["model_config"]["name"] == "rtaw_plus"
    assert ckpt["frames"] == 512
    assert all(torch.isfinite(v).all() for v in ckpt["model"]["actor"].values())


@pytest.mark.parametrize("interop", [False, True])
def test_rtaw_plus_trains_with_a_critic_blind_to_the_fleet(train_cfg, tmp_path, interop) -> None:
    """The ``model.critic_fleet=false`` ablation trains on both routes and its checkpoint
    rebuilds the same critic."""
    overrides = ["scenario=poc", "frames=512", "selection.every_frames=512", f"interop={interop}",
                 "model=rtaw_plus", "model.critic_fleet=false"]  # fmt: skip
    result = train(train_cfg(overrides), tmp_path)
    ckpt = load_checkpoint(result.last_checkpoint)
    assert ckpt["model_config"]["critic_fleet"] is False
    assert not any(k.startswith("fleet_embed") for k in ckpt["model"]["critic"])
    assert all(torch.isfinite(v).all() for v in ckpt["model"]["critic"].values())


def test_interop_route_trains_through_pettingzoo_wrapper(train_cfg, tmp_path: Path) -> None:
    """A few PPO updates through torchrl's PettingZooWrapper with loss_mask_key."""
    result = train(
        train_cfg(["scenario=poc", "frames=1024", "selection.every_frames=512", "interop=true"]),
        tmp_path,
    )
    torch.manual_seed(0)  # train() seeds torch with cfg.seed=0 before building the networks
    init, _ = build_networks({"embed_dim": 16, "head_dim": 8, "critic_hidden": 32})
    trained = _actor_state(result.last_checkpoint)
    assert load_checkpoint(result.last_checkpoint)["frames"] == 1024
    assert any(not torch.equal(init.state_dict()[k], trained[k]) for k in trained)
    assert all(torch.isfinite(v).all() for v in trained.values())


def test_two_worker_collector(train_cfg, tmp_path: Path) -> None:
    result = train(
        train_cfg(
            [
                "scenario=poc",
                "frames=1024",
                "selection.every_frames=1024",
                "collector.workers=2",
                "collector.envs_per_worker=4",
            ]
        ),
        tmp_path,
    )
    assert result.frames == 1024


def test_training_outputs(train_cfg, tmp_path: Path) -> None:
    result = train(train_cfg(TINY), tmp_path)
    assert (tmp_path / "training_curve.png").stat().st_size > 1000
    assert (tmp_path / "logs" / "metrics.csv").is_file()
    ckpt = load_checkpoint(result.best_checkpoint)
    assert set(ckpt) >= {"model", "optimizer", "config", "versions", "frames", "command"}
    assert ckpt["versions"]["torchrl"] == "0.14.1"
    assert not list((tmp_path / "checkpoints").glob(".*tmp"))


def test_checkpoint_for_other_features_fails_clearly(tmp_path: Path) -> None:
    actor, critic = build_networks({})
    path = save_checkpoint(
        tmp_path / "x.pt",
        {"model": {"actor": actor.state_dict(), "critic": critic.state_dict()}, "model_config": {}},
    )
    ckpt = torch.load(path, weights_only=True)
    ckpt["features"] = {"robots": ["x", "y"], "tasks": FEATURES["rtaw"]["tasks"]}
    torch.save(ckpt, path)
    with pytest.raises(ConfigError, match="trained on observation features"):
        load_checkpoint(path)


@pytest.mark.parametrize(
    ("override", "message"),
    [
        ("algo.minibatch_size=100", "must be a multiple of algo.minibatch_size"),
        ("collector.envs_per_worker=7", "must be a multiple of"),
        ("logger=foo", "available: csv, mlflow, none, tensorboard, wandb"),
        ("resume=missing.pt", "checkpoint not found"),
        ("+model.embed_dmi=8", "unknown config key 'model.embed_dmi'"),
    ],
)
def test_train_cli_errors(override: str, message: str, cli, tmp_path: Path) -> None:
    result = cli(
        "train",
        "scenario=poc",
        "frames=1024",
        "algo=ppo_paper",
        f"output_dir={tmp_path}",
        "progress=false",
        override,
    )
    assert result.code == 2
    assert message in result.err
    assert len(result.err.strip().splitlines()) == 1
    assert "Traceback" not in result.err + result.out


def test_train_then_eval_cli_on_other_sizes(tmp_path: Path) -> None:
    """rtaw-train smoke run, then rtaw-eval runs its checkpoint with other M, N, navigator."""
    bin_dir = Path(sys.executable).parent
    run = subprocess.run(
        [str(bin_dir / "rtaw-train"), *TINY, f"output_dir={tmp_path / 'run'}", "progress=false"],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert run.returncode == 0, run.stderr
    # The last word: best.pt against the setting's best rule on the evaluation seeds.
    assert run.stdout.strip().splitlines()[-1].startswith("verdict: best.pt "), run.stdout
    ckpt = tmp_path / "run" / "checkpoints" / "best.pt"
    ev = subprocess.run(
        [
            str(bin_dir / "rtaw-eval"),
            "policy=[mpdm,checkpoint]",
            f"checkpoint={ckpt}",
            "sim.num_robots=20",
            "sim.queue_len=5",
            "sim.num_tasks=50",
            "navigator=direct",
            "seeds=[0]",
            f"output={tmp_path / 'r.json'}",
            "progress=false",
        ],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert ev.returncode == 0, ev.stderr
    assert checkpoint_labels([str(ckpt)])[0] in ev.stdout


def test_interrupted_save_keeps_previous_checkpoint(tmp_path: Path, monkeypatch) -> None:
    """A crash in the middle of writing leaves the previous checkpoint intact and loadable."""
    actor, critic = build_networks({})
    payload = {
        "model": {"actor": actor.state_dict(), "critic": critic.state_dict()},
        "model_config": {},
        "frames": 1,
    }
    path = save_checkpoint(tmp_path / "last.pt", payload)

    def crash(obj, fh) -> None:
        fh.write(b"partial")
        raise KeyboardInterrupt

    monkeypatch.setattr(torch, "save", crash)
    with pytest.raises(KeyboardInterrupt):
        save_checkpoint(path, {**payload, "frames": 2})
    monkeypatch.undo()
    assert load_checkpoint(path)["frames"] == 1
    assert [p.name for p in tmp_path.iterdir()] == ["last.pt"]


@pytest.mark.parametrize("launcher", ["basic", "joblib"])
def test_multirun_sweep_trains_each_job_into_its_own_folder(cli, tmp_path: Path, launcher: str):
    """``rtaw-train -m seed=0,1``: one run folder per job, each with its checkpoints."""
    result = cli(
        "train", "--multirun", "seed=0,1", "scenario=poc", "frames=256",
        "algo.frames_per_batch=256", "algo.minibatch_size=64", "collector.envs_per_worker=4",
        "selection.seeds=[1000]", "selection.every_frames=256", "progress=false",
        f"hydra/launcher={launcher}", f"hydra.sweep.dir={tmp_path / 'sweep'}",
    )  # fmt: skip
    assert result.code == 0, result.err
    runs = sorted((tmp_path / "sweep").glob("*/checkpoints/last.pt"))
    assert [p.parts[-3] for p in runs] == ["0", "1"]
    seeds = {load_checkpoint(p)["config"]["seed"] for p in runs}
    assert seeds == {0, 1}


def test_resumed_run_keeps_its_whole_evaluation_history(train_cfg, tmp_path: Path) -> None:
    """The checkpoint carries every evaluation, so a resumed run draws its whole curve."""
    first = train(train_cfg(TINY), tmp_path / "a")
    resumed = train(
        train_cfg([*TINY[:1], "frames=2048", "selection.every_frames=512",
                   "collector.envs_per_worker=4", f"resume={first.last_checkpoint}"]),
        tmp_path / "b",
    )  # fmt: skip
    frames = [row["frames"] for row in resumed.history]
    assert frames == [0, 512, 1024, 1536, 2048]
    assert load_checkpoint(resumed.last_checkpoint)["history"] == resumed.history


def test_interop_advantages_are_standardised_over_the_acting_rows_only() -> None:
    """Non-acting rows (meaningless on the interop route) must not shift the statistics."""
    from tensordict import TensorDict

    from rtaw_marl.training.interop import INTEROP_KEYS, standardize_acting_advantage

    mask = torch.tensor([[True, False], [False, True], [True, False]])
    advantage = torch.tensor([[[1.0], [100.0]], [[-50.0], [3.0]], [[5.0], [7.0]]])
    data = TensorDict({"agents": {"advantage": advantage, "mask": mask}}, batch_size=[3])
    standardize_acting_advantage(data, INTEROP_KEYS)
    out = data["agents", "advantage"]
    acting = torch.tensor([1.0, 3.0, 5.0])
    expected = (acting - acting.mean()) / acting.std(unbiased=False)
    assert torch.allclose(out.squeeze(-1)[mask], expected)
    assert (out.squeeze(-1)[~mask] == 0).all()
