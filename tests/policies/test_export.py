"""Exported actors (TorchScript, ONNX) against the Python policies they come from."""

from __future__ import annotations

import dataclasses
import json
import sys
from pathlib import Path

import numpy as np
import onnx
import onnxruntime
import pytest
import torch

from rtaw_marl import warehouse_v1
from rtaw_marl.decision.features import feature_shapes
from rtaw_marl.errors import ConfigError
from rtaw_marl.policies import export as export_module
from rtaw_marl.policies.export import (
    SPEC_NAME,
    ExportCheckError,
    ExportConfig,
    export_format,
    export_policy,
    load_exported,
)
from rtaw_marl.policies.export_check import check_exported, record_decisions
from rtaw_marl.policies.export_spec import COLUMNS, INPUTS, input_spec
from rtaw_marl.policies.network import load_policy

pytestmark = pytest.mark.integration

#: The paper's network and RTAW+ (the generalist: logits in the hundreds).
POLICIES = {"rtaw": "A_astar_m10", "rtaw_plus": "generalist_plus"}
#: A checked episode unlike the tracing sizes (2 decisions, 3 slots, 4 robots).
SMALL = {"num_robots": 6, "queue_len": 5, "num_tasks": 30}
#: Another fleet, queue, layout and navigator than the export's check saw.
OTHER = {"num_robots": 23, "queue_len": 12, "num_tasks": 40, "layout": "C", "navigator": "direct"}
#: The smallest sizes: one robot (no rivals: every rival row padding), one slot.
TINY = {"num_robots": 1, "queue_len": 1, "num_tasks": 10}


@pytest.fixture(scope="module")
def exported(tmp_path_factory) -> dict[tuple[str, str], Path]:
    """Every (model, suffix) exported once, checked on :data:`SMALL`."""
    folder = tmp_path_factory.mktemp("export")
    out = {}
    for model, name in POLICIES.items():
        for suffix in (".pt", ".onnx"):
            config = ExportConfig(output=str(folder / f"{name}{suffix}"), **SMALL)
            path, report = export_policy(name, config)
            assert report.ok, report.summary()
            assert report.decisions == SMALL["num_tasks"]
            out[model, suffix] = path
    return out


@pytest.mark.parametrize("suffix", [".pt", ".onnx"])
@pytest.mark.parametrize("model", list(POLICIES))
def test_export_writes_the_model_and_its_specification(
    exported: dict[tuple[str, str], Path], model: str, suffix: str
) -> None:
    path = exported[model, suffix]
    policy = load_policy(POLICIES[model])
    sidecar = json.loads(Path(f"{path}.json").read_text())
    assert sidecar["model"] == model
    assert sidecar["model_format"] == export_format(path)
    assert sidecar["source"]["policy"] == POLICIES[model]
    assert [spec["name"] for spec in sidecar["inputs"]] == list(policy.net.in_keys)
    assert sidecar["check"]["ok"] is True
    assert sidecar["check"]["choices_equal"] == SMALL["num_tasks"]
    assert sidecar["check"]["max_abs_diff"] <= 1e-3
    assert sidecar["check"]["env"]["num_robots"] == SMALL["num_robots"]
    # The same specification is embedded in the model file.
    if suffix == ".pt":
        extra = {SPEC_NAME: ""}
        torch.jit.load(path, _extra_files=extra)
        embedded = json.loads(extra[SPEC_NAME])
    else:
        proto = onnx.load(path)
        onnx.checker.check_model(proto)
        embedded = json.loads({p.key: p.value for p in proto.metadata_props}[SPEC_NAME])
        dims = {
            node.name: [d.dim_param or d.dim_value for d in node.type.tensor_type.shape.dim]
            for node in proto.graph.input
        }
        assert dims == {spec["name"]: spec["shape"] for spec in sidecar["inputs"]}
    assert embedded == {key: value for key, value in sidecar.items() if key != "check"}
    assert not list(path.parent.glob(".*tmp"))


@pytest.mark.parametrize("env", [OTHER, TINY], ids=["N12_M23", "N1_M1"])
@pytest.mark.parametrize("suffix", [".pt", ".onnx"])
@pytest.mark.parametrize("model", list(POLICIES))
def test_exported_model_matches_on_other_fleet_and_queue_sizes(
    exported: dict[tuple[str, str], Path], model: str, suffix: str, env: dict
) -> None:
    """Dynamic dimensions: traced at N=3, M=4, checked at N=5, M=6, here at N=12, M=23
    on another layout and navigator and at N=1, M=1, every decision of an episode in
    one batch."""
    path = exported[model, suffix]
    policy = load_policy(POLICIES[model])
    inputs, actions = record_decisions(policy, env, seed=7)
    assert inputs["action_mask"].shape == (env["num_tasks"], env["queue_len"])
    run = load_exported(path.read_bytes(), export_format(path))
    report = check_exported(run, policy.net, inputs, actions, atol=1e-4, rtol=1e-4)
    assert report.ok, report.summary()
    # One decision at a time (batch of 1) gives the same logits as the batch.
    first = {key: value[:1] for key, value in inputs.items()}
    np.testing.assert_allclose(run(first)[0], run(inputs)[0], rtol=1e-5, atol=1e-5)


def _onnx_act(session: onnxruntime.InferenceSession, obs: dict) -> int:
    """docs/export.md's example: one env observation -> the ONNX model's action."""
    names = [node.name for node in session.get_inputs()]
    feeds = {
        name: obs["action_mask"].astype(bool)[None]
        if name == "action_mask"
        else obs["observation"][name][None]
        for name in names
    }
    return int(session.run(None, feeds)[0][0].argmax())


def _torchscript_act(module: torch.jit.ScriptModule, names: list[str], obs: dict) -> int:
    """docs/export.md's example with ``torch.jit.load``."""
    feeds = {
        name: torch.from_numpy(obs["action_mask"].astype(bool))[None]
        if name == "action_mask"
        else torch.from_numpy(np.array(obs["observation"][name]))[None]
        for name in names
    }
    with torch.no_grad():
        return int(module(**feeds)[0].argmax())


@pytest.mark.parametrize("model", list(POLICIES))
def test_docs_examples_choose_as_the_python_policy_on_env_observations(
    exported: dict[tuple[str, str], Path], model: str
) -> None:
    policy = load_policy(POLICIES[model])
    session = onnxruntime.InferenceSession(str(exported[model, ".onnx"]))
    module = torch.jit.load(exported[model, ".pt"])
    names = [spec["name"] for spec in input_spec(policy.net.in_keys)]
    env = warehouse_v1.env(num_robots=12, queue_len=8, num_tasks=25, layout="B")
    env.reset(seed=3)
    decisions = 0
    for agent in env.agent_iter():
        obs, _, terminated, truncated, _ = env.last()
        if terminated or truncated:
            env.step(None)
            continue
        action = policy.act(obs)
        assert _onnx_act(session, obs) == action, agent
        assert _torchscript_act(module, names, obs) == action, agent
        env.step(action)
        decisions += 1
    assert decisions == 25


def test_check_fails_on_a_model_that_disagrees() -> None:
    """The check is real: shifted logits, a swapped choice or a lost mask fail it."""
    policy = load_policy(POLICIES["rtaw_plus"])
    inputs, actions = record_decisions(policy, SMALL, seed=0)
    keys = policy.net.in_keys

    def eager(feeds: dict) -> np.ndarray:
        with torch.no_grad():
            logits = policy.net(*(torch.from_numpy(feeds[k]) for k in keys)).numpy()
        return np.where(feeds["action_mask"], logits, -np.inf)

    assert check_exported(eager, policy.net, inputs, actions, 1e-4, 1e-4).ok
    shifted = check_exported(lambda f: eager(f) + 0.5, policy.net, inputs, actions, 1e-4, 1e-4)
    assert not shifted.ok
    assert not shifted.within_tolerance
    assert shifted.max_abs_diff == pytest.approx(0.5, rel=1e-3)
    assert shifted.choices_equal == len(actions)  # a constant shift keeps the argmax
    swapped = check_exported(eager, policy.net, inputs, (actions + 1) % 5, 1e-4, 1e-4)
    assert not swapped.ok
    assert swapped.choices_equal < len(actions)
    unmasked = check_exported(
        lambda f: np.nan_to_num(eager(f), neginf=-1e9), policy.net, inputs, actions, 1e-4, 1e-4
    )
    assert not unmasked.ok
    assert not unmasked.masked_equal


def test_export_that_disagrees_writes_nothing(tmp_path: Path, monkeypatch) -> None:
    def off_by_one(data: bytes, fmt: str):
        run = load_exported(data, fmt)
        return lambda feeds: run(feeds) + 1.0

    monkeypatch.setattr(export_module, "load_exported", off_by_one)
    out = tmp_path / "policy.pt"
    with pytest.raises(ExportCheckError, match=r"disagrees with A_astar_m10: .* nothing written"):
        export_policy("A_astar_m10", ExportConfig(output=str(out), **SMALL))
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(
    ("source", "output", "message"),
    [
        ("nope", "x.onnx", "neither a checkpoint file nor a shipped pretrained policy"),
        ("A_astar_m10", "x.onnx.txt", r"output must end in \.pt \(TorchScript\) or \.onnx"),
        ("A_astar_m10", "", "output=FILE.pt"),
    ],
)
def test_bad_input_is_a_config_error(tmp_path: Path, source: str, output: str, message: str):
    config = ExportConfig(output=str(tmp_path / output) if output else "")
    with pytest.raises(ConfigError, match=message):
        export_policy(source, config)
    assert list(tmp_path.iterdir()) == []


def test_onnx_without_the_export_extra_names_it(tmp_path: Path, monkeypatch) -> None:
    monkeypatch.setitem(sys.modules, "onnxscript", None)
    with pytest.raises(ConfigError, match=r"needs the export extra .*rtaw_marl\[export\]"):
        export_policy("A_astar_m10", ExportConfig(output=str(tmp_path / "a.onnx")))


def test_specification_covers_every_input_column() -> None:
    """Every column of every input is documented, with the env's shapes."""
    shapes = feature_shapes(num_robots=7, queue_len=5)
    sizes = {"batch": 1, "tasks": 5, "robots": 7}
    for key, (shape, columns, _) in INPUTS.items():
        assert set(COLUMNS[key]) == set(columns), key
        assert tuple(sizes.get(d, d) for d in shape[1:]) == shapes[key], key
        for column in input_spec((key,))[0]["columns"]:
            assert column["meaning"], column
            assert column["unit"], column
            assert column["range"], column
    assert set(ExportConfig().env_args()) == {"num_tasks"}
    assert dataclasses.asdict(ExportConfig())["atol"] == 1e-4


def test_docs_export_md_lists_every_column_in_order() -> None:
    """docs/export.md's tables hold every column of every input at its index."""
    text = (Path(__file__).resolve().parents[2] / "docs" / "export.md").read_text()
    for key, (shape, columns, _) in INPUTS.items():
        dims = ", ".join(map(str, shape))
        assert f"**`{key}`** `{'bool' if key == 'action_mask' else 'float32'} [{dims}]`" in text
        if key == "agent":  # "same columns" as robots
            continue
        for i, column in enumerate(columns):
            assert f"| {i} | `{column}` |" in text, (key, column)
