"""Checkpoints are data, never code: crafted files are refused before anything runs, and
files whose metadata does not fit their weights give one clear error."""

from __future__ import annotations

import os
from pathlib import Path

import pytest
import torch

from rtaw_marl.errors import ConfigError
from rtaw_marl.models.checkpoint import (
    build_networks,
    load_checkpoint,
    load_networks,
    plain_model,
    save_checkpoint,
)
from rtaw_marl.models.config import RTAWConfig, RTAWPlusConfig
from rtaw_marl.policies.network import load_policy
from rtaw_marl.policies.pretrained.registry import PRETRAINED, pretrained_path


class _Payload:
    """Unpickling this object creates a file: what a malicious checkpoint would do."""

    def __init__(self, marker: Path) -> None:
        self.marker = marker

    def __reduce__(self) -> tuple[object, tuple[str, int]]:
        return os.open, (str(self.marker), os.O_CREAT | os.O_WRONLY)


def _save(path: Path, config: RTAWConfig | RTAWPlusConfig, **overrides: object) -> Path:
    actor, critic = build_networks(config)
    payload = {
        "model": {"actor": actor.state_dict(), "critic": critic.state_dict()},
        "model_config": plain_model(config),
        "frames": 0,
        "iteration": 0,
    }
    payload.update(overrides)
    return save_checkpoint(path, payload)


def test_malicious_pickle_is_refused_before_it_runs(tmp_path: Path) -> None:
    marker = tmp_path / "pwned"
    path = tmp_path / "evil.pt"
    # A real checkpoint with one crafted entry: it passes every format check but must
    # never reach them.
    _save(path, RTAWConfig(), eval=_Payload(marker))
    with pytest.raises(ConfigError, match="holds more than plain data"):
        load_checkpoint(path)
    assert not marker.exists()
    with pytest.raises(ConfigError, match="holds more than plain data"):
        load_policy(path)
    assert not marker.exists()


def test_saved_checkpoints_are_plain_data(tmp_path: Path) -> None:
    path = _save(tmp_path / "ok.pt", RTAWPlusConfig())
    raw = torch.load(path, weights_only=True)  # no allow-list needed for new files
    assert isinstance(raw["versions"]["torch"], str)
    actor, critic = load_networks(load_checkpoint(path), path)
    assert actor.in_keys == ("relations", "rivals", "action_mask")
    assert "robots" in critic.in_keys


@pytest.mark.parametrize("name", sorted(PRETRAINED)[:4])
def test_shipped_checkpoints_load_weights_only(name: str) -> None:
    load_policy(pretrained_path(name))


def test_first_release_checkpoint_loads_weights_only() -> None:
    load_policy(Path(__file__).parents[1] / "data" / "rtaw_v1_A_astar_m10.pt")


def test_missing_model_config_is_one_error(tmp_path: Path) -> None:
    path = _save(tmp_path / "a.pt", RTAWConfig())
    ckpt = torch.load(path, weights_only=True)
    del ckpt["model_config"]
    torch.save(ckpt, path)
    with pytest.raises(ConfigError, match="no 'model_config'"):
        load_policy(path)


def test_weights_that_do_not_fit_the_model_config(tmp_path: Path) -> None:
    # Weights of a wider network under the default model_config.
    wide = RTAWConfig(embed_dim=32)
    path = _save(tmp_path / "a.pt", wide, model_config=plain_model(RTAWConfig()))
    with pytest.raises(ConfigError, match="actor weights do not fit its model_config"):
        load_policy(path)


def test_weights_of_another_model(tmp_path: Path) -> None:
    actor, critic = build_networks(RTAWConfig())
    path = _save(
        tmp_path / "a.pt",
        RTAWPlusConfig(),
        model={"actor": actor.state_dict(), "critic": critic.state_dict()},
    )
    with pytest.raises(ConfigError, match="do not fit"):
        load_policy(path)


def test_missing_weights(tmp_path: Path) -> None:
    path = _save(tmp_path / "a.pt", RTAWConfig(), model={"critic": {}})
    with pytest.raises(ConfigError, match="no actor weights"):
        load_policy(path)


def test_not_a_torch_file(tmp_path: Path) -> None:
    path = tmp_path / "a.pt"
    path.write_bytes(b"\x00\x01garbage")
    with pytest.raises(ConfigError, match="cannot read checkpoint"):
        load_checkpoint(path)


@pytest.mark.parametrize(
    ("case", "message"),
    [
        ("malicious", "holds more than plain data (it would call posix.open"),
        ("no model_config", "has no 'model_config' dict"),
        ("wrong weights", "actor weights do not fit its model_config"),
        ("garbage", "cannot read checkpoint"),
    ],
)
def test_bad_checkpoints_through_the_cli(cli, tmp_path: Path, case: str, message: str) -> None:
    """``rtaw-eval policy=checkpoint``: one line, exit 2, and a crafted file runs nothing."""
    marker = tmp_path / "pwned"
    path = tmp_path / "bad.pt"
    if case == "malicious":
        _save(path, RTAWConfig(), eval=_Payload(marker))
    elif case == "no model_config":
        ckpt = torch.load(_save(path, RTAWConfig()), weights_only=True)
        del ckpt["model_config"]
        torch.save(ckpt, path)
    elif case == "wrong weights":
        _save(path, RTAWConfig(embed_dim=32), model_config=plain_model(RTAWConfig()))
    else:
        path.write_bytes(b"PK\x03\x04 not a checkpoint")
    result = cli("eval", "policy=[mpdm,checkpoint]", f"checkpoint={path}", "seeds=[0]",
                 "env.num_tasks=20", "progress=false")  # fmt: skip
    assert result.code == 2
    assert message in result.err
    assert len(result.err.strip().splitlines()) == 1
    assert "Traceback" not in result.err
    assert not marker.exists()
