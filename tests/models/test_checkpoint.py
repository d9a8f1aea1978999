"""Checkpoints are data, never code: crafted files are refused before anything runs, and
files whose metadata does not fit their weights give one clear error."""

from __future__ import annotations

import os
import pickle
import zipfile
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

pytestmark = pytest.mark.unit


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


def _flip_tensor_bytes(path: Path, count: int = 16) -> None:
    """Flip ``count`` bytes in the middle of the first stored tensor (as a bad disk or
    transfer would): the archive still opens, only its CRC tells."""
    with zipfile.ZipFile(path) as archive:
        info = archive.getinfo("archive/data/0")
    raw = bytearray(path.read_bytes())
    # The local header: 30 bytes, then the name and the extra field (lengths at 26, 28).
    name_len = int.from_bytes(raw[info.header_offset + 26 : info.header_offset + 28], "little")
    extra_len = int.from_bytes(raw[info.header_offset + 28 : info.header_offset + 30], "little")
    data = info.header_offset + 30 + name_len + extra_len
    middle = data + info.file_size // 2
    for i in range(middle, middle + count):
        raw[i] ^= 0xFF
    path.write_bytes(bytes(raw))


def _save_poisoned(path: Path, net: str, value: float, **overrides: object) -> Path:
    """A checkpoint whose ``net`` has one weight set to ``value`` (NaN or inf)."""
    actor, critic = build_networks(RTAWConfig())
    state = {"actor": actor.state_dict(), "critic": critic.state_dict()}
    state[net]["encoder.robot_embed.0.weight"][0, 0] = value
    return _save(path, RTAWConfig(), model=state, **overrides)


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
    with pytest.raises(ConfigError, match=r"a.pt is not a torch checkpoint \(not a zip archive\)"):
        load_checkpoint(path)


@pytest.mark.parametrize(
    ("case", "message"),
    [
        ("malicious", "holds more than plain data (it would call posix.open"),
        ("no model_config", "has no 'model_config' dict"),
        ("wrong weights", "actor weights do not fit its model_config"),
        ("garbage", "is not a torch checkpoint (not a zip archive)"),
        ("folder", "bad.pt is a folder, not a file"),
        ("crc", "is damaged: archive/data/0 fails its CRC check"),
        (
            "nan",
            "model.actor.encoder.robot_embed.0.weight holds 1 non-finite value(s) (NaN or inf)",
        ),
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
    elif case == "folder":
        path.mkdir()
    elif case == "crc":
        _flip_tensor_bytes(_save(path, RTAWConfig()))
    elif case == "nan":
        _save_poisoned(path, "actor", float("nan"))
    else:
        path.write_bytes(b"PK\x03\x04 not a checkpoint")
    result = cli("eval", "policy=[mpdm,checkpoint]", f"checkpoint={path}", "seeds=[0]",
                 "sim.num_tasks=20", "progress=false")  # fmt: skip
    assert result.code == 2
    assert message in result.err
    assert len(result.err.strip().splitlines()) == 1
    assert "Traceback" not in result.err
    assert not marker.exists()


def _raw_pickle(path: Path) -> None:
    path.write_bytes(pickle.dumps({"format": "rtaw_marl.checkpoint/1"}))


def _legacy(path: Path) -> None:
    torch.save({"a": torch.ones(2)}, path, _use_new_zipfile_serialization=False)


def _zip_of_text(path: Path) -> None:
    with zipfile.ZipFile(path, "w") as archive:
        archive.writestr("notes.txt", "hello")


@pytest.mark.parametrize(
    ("case", "message"),
    [
        ("folder", "x.pt is a folder, not a file"),
        ("fifo", "x.pt is a FIFO, not a file"),
        ("dangling", "x.pt is a dangling symlink (its target is missing)"),
        ("loop", "x.pt is a symlink loop"),
        ("empty", "x.pt is empty (0 bytes)"),
        ("text", "x.pt is not a torch checkpoint (not a zip archive)"),
        ("raw pickle", "x.pt is a raw pickle (or torch's legacy non-zip format), which is "
                       "never loaded as it could run code"),
        ("legacy", "x.pt is a raw pickle (or torch's legacy non-zip format)"),
        ("zip", "x.pt is a zip archive but not a torch checkpoint"),
        ("crc", "x.pt is damaged: archive/data/0 fails its CRC check"),
        ("nan actor", "model.actor.encoder.robot_embed.0.weight holds 1 non-finite value(s)"),
        ("inf critic", "model.critic.encoder.robot_embed.0.weight holds 1 non-finite value(s)"),
        ("nan optimizer", "optimizer.state.0.exp_avg holds 2 non-finite value(s)"),
    ],
)  # fmt: skip
def test_what_is_not_an_intact_finite_checkpoint(tmp_path: Path, case: str, message: str) -> None:
    """Each is one line naming the path and what it is, for evaluation and resume alike;
    none reads as "not found", none passes on torch's advice to load unsafely."""
    path = tmp_path / "x.pt"
    text = tmp_path / "notes.txt"
    text.write_text("not a checkpoint\n")
    if case == "folder":
        path.mkdir()
    elif case == "fifo":
        os.mkfifo(path)
    elif case == "dangling":
        path.symlink_to(tmp_path / "gone.pt")
    elif case == "loop":
        path.symlink_to(path)
    elif case == "empty":
        path.touch()
    elif case == "text":
        path.symlink_to(text)
    elif case == "raw pickle":
        _raw_pickle(path)
    elif case == "legacy":
        _legacy(path)
    elif case == "zip":
        _zip_of_text(path)
    elif case == "crc":
        _flip_tensor_bytes(_save(path, RTAWConfig()))
    elif case == "nan actor":
        _save_poisoned(path, "actor", float("nan"))
    elif case == "inf critic":
        _save_poisoned(path, "critic", float("inf"))
    else:
        moments = {"exp_avg": torch.tensor([1.0, float("nan"), float("-inf")])}
        _save(path, RTAWConfig(), optimizer={"state": {0: moments}, "param_groups": []})
    for load in (load_checkpoint, load_policy):
        with pytest.raises(ConfigError) as raised:
            load(str(path))
        line = str(raised.value)
        assert message in line
        assert str(path) in line
        assert "\n" not in line
        assert "weights_only" not in line
