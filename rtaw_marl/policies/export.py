"""Export a trained actor to TorchScript or ONNX, checked against the Python policy.

:func:`export_policy` turns the actor of a checkpoint or shipped policy into a
standalone model whose inputs are the network's observation entries with a leading
batch axis and named dynamic dimensions (``batch``, ``tasks`` = ``N``, and ``robots`` =
``M`` for the paper's network), and whose output is ``logits [batch, tasks]``, ``-inf``
on the slots the action mask leaves out; the action is their argmax. The file suffix
picks the format: ``.pt`` is a traced TorchScript module (``torch.jit.load``), ``.onnx``
an ONNX model (``torch.onnx.export``'s dynamo exporter; ``onnxruntime`` runs it).

Both are traced on small made-up inputs (2 decisions, 3 slots, 4 robots) and then
*checked*: an episode of ``warehouse_v1`` is played with the Python policy
(:meth:`~rtaw_marl.policies.network.NetworkPolicy.act`), the network inputs of every
decision are recorded, and the exported model, loaded back from the bytes to be
written, must give the eager network's logits within ``atol + rtol * |logit|`` and the
policy's choice at every decision. Only then are the model and its sidecar
``<output>.json`` written, atomically: the input specification of
:mod:`~rtaw_marl.policies.export_spec`, the source policy and the check's figures (the
same but the check is embedded in the model, so the file describes itself).
"""

from __future__ import annotations

import hashlib
import importlib.util
import io
import json
import logging
import math
import numbers
import os
import warnings
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from rtaw_marl.errors import EXTRAS, ConfigError, RtawError, extra_message, missing_extra

# Without the training extra: one error that names it (errors.missing_extra), no traceback
# of a bare ModuleNotFoundError.
try:
    import torch
    from torch import nn
except ModuleNotFoundError as exc:
    raise missing_extra(exc, __name__, "train") from None

from rtaw_marl.models.checkpoint import Actor, library_versions, load_checkpoint
from rtaw_marl.models.rtaw import RTAWActor
from rtaw_marl.policies.export_check import CheckReport, Runner, check_exported, record_decisions
from rtaw_marl.policies.export_spec import DIMS, NORMALISATION, OUTPUT, input_spec
from rtaw_marl.policies.network import checkpoint_path, load_policy
from rtaw_marl.utils.atomic import atomic_write
from rtaw_marl.utils.runs import claim_file
from rtaw_marl.utils.signals import signals_held

__all__ = [
    "EXPORT_FORMAT",
    "FORMATS",
    "SPEC_NAME",
    "TOLERANCES",
    "ExportCheckError",
    "ExportConfig",
    "MaskedActor",
    "check_tolerance",
    "export_format",
    "export_policy",
    "load_exported",
    "masked_actor",
]

EXPORT_FORMAT = "rtaw_marl.export/1"
#: Output suffix -> format.
FORMATS = {".pt": "torchscript", ".onnx": "onnx"}
#: Name of the specification inside a TorchScript file (``torch.jit.load(_extra_files=)``)
#: and key of the ONNX model's metadata.
SPEC_NAME = "rtaw_export.json"
#: Sizes of the made-up tracing inputs: unlike any real queue or fleet, so that every
#: check also exercises the dynamic dimensions.
_TRACE = {"batch": 2, "tasks": 3, "robots": 4}


#: ``atol`` and ``rtol`` -> (largest value, why): past it the check checks nothing.
#: Logits reach the hundreds; float32 rounding alone is about 1e-7 of a logit, and
#: onnxruntime's reordering 1.5e-4 at 290 (docs/export.md).
TOLERANCES: dict[str, tuple[float, str]] = {
    "atol": (
        1.0,
        "a logit difference of 1 already scales a slot's probability by e (2.7), so a "
        "larger atol would let a different policy pass",
    ),
    "rtol": (
        0.01,
        "1% of a logit in the hundreds is several units while float32 rounding is about "
        "1e-7 of it, so a larger rtol would let a different policy pass",
    ),
}


def check_tolerance(key: str, value: object) -> float:
    """``value`` of the tolerance ``key`` (``atol``, ``rtol``), checked: a finite number
    from 0 to its :data:`TOLERANCES` limit. ``inf`` would switch the check off, and a
    huge one overflows float32 and fails every logit.

    Raises:
        ConfigError: Not a number, not finite, negative or over the limit; the message
            gives the range and why.
    """
    limit, why = TOLERANCES[key]
    if not isinstance(value, numbers.Real) or isinstance(value, bool):
        raise ConfigError(
            f"{key} must be a number >= 0 and <= {limit:g}, got {value!r} ({type(value).__name__})"
        )
    number = float(value)
    if not (math.isfinite(number) and 0 <= number <= limit):
        raise ConfigError(f"{key} must be >= 0 and <= {limit:g}, got {number:g}: {why}")
    return number


class ExportCheckError(RtawError):
    """The exported model disagrees with the Python policy (nothing was written)."""


class MaskedActor(nn.Module):
    """An actor whose logits are ``-inf`` on the slots ``action_mask`` leaves out.

    Use :func:`masked_actor`: it picks the subclass whose ``forward`` names the actor's
    inputs, so the exported models' inputs carry these names.

    Args:
        actor: The trained actor (``in_keys`` name its inputs, ``action_mask`` last).
    """

    def __init__(self, actor: Actor) -> None:
        super().__init__()
        self.actor = actor.eval()
        self.in_keys: tuple[str, ...] = actor.in_keys

    def masked(self, *inputs: torch.Tensor) -> torch.Tensor:
        """``logits [*, N]`` of ``inputs`` in ``in_keys`` order."""
        return self.actor(*inputs).masked_fill(~inputs[-1], float("-inf"))


class _MaskedRTAW(MaskedActor):
    def forward(
        self, robots: torch.Tensor, tasks: torch.Tensor, agent: torch.Tensor,
        action_mask: torch.Tensor,
    ) -> torch.Tensor:  # fmt: skip
        return self.masked(robots, tasks, agent, action_mask)


class _MaskedRTAWPlus(MaskedActor):
    def forward(
        self, relations: torch.Tensor, rivals: torch.Tensor, action_mask: torch.Tensor
    ) -> torch.Tensor:
        return self.masked(relations, rivals, action_mask)


def masked_actor(actor: Actor) -> MaskedActor:
    """The :class:`MaskedActor` of ``actor``, its ``forward`` arguments named."""
    wrapper = _MaskedRTAW if isinstance(actor, RTAWActor) else _MaskedRTAWPlus
    return wrapper(actor).eval()


@dataclass(kw_only=True)
class ExportConfig:
    """The options of ``rtaw-export POLICY KEY=VALUE ...`` (:func:`export_policy`).

    Attributes:
        output: The file to write: ``*.pt`` (TorchScript) or ``*.onnx`` (ONNX); the
            specification goes beside it, to ``<output>.json``.
        scenario: The checked episode's setting (a name of ``rtaw_marl.scenarios``);
            ``None``: the env's defaults.
        layout: Its layout (``A`` ... ``E``, ``shelves``, a map file, ...); ``None``:
            the scenario's.
        navigator: Its navigator (``direct``, ``astar``, ``sipp``, ``cbs``).
        tasks: Its task stream (``random``, ``designated``, ...).
        num_robots: ``M`` of the checked episode; ``None``: the scenario's.
        queue_len: ``N`` of the checked episode; ``None``: the scenario's.
        num_tasks: Decisions checked (the episode's length).
        seed: The checked episode's seed.
        atol: Absolute tolerance of the check: every logit of the exported model must be
            within ``atol + rtol * |logit|`` of the Python network's; from 0 to 1
            (:data:`TOLERANCES`).
        rtol: Relative tolerance of the check; from 0 to 0.01.

    Raises:
        ConfigError: ``atol`` or ``rtol`` is not a finite number in its range
            (:func:`check_tolerance`).
    """

    output: str = ""
    scenario: str | None = None
    layout: str | None = None
    navigator: str | None = None
    tasks: str | None = None
    num_robots: int | None = None
    queue_len: int | None = None
    num_tasks: int = 100
    seed: int = 0
    atol: float = 1e-4
    rtol: float = 1e-4

    def __post_init__(self) -> None:
        for key in TOLERANCES:
            check_tolerance(key, getattr(self, key))

    def env_args(self) -> dict[str, Any]:
        """The ``warehouse_v1.env`` arguments of the checked episode."""
        keys = ("scenario", "layout", "navigator", "tasks", "num_robots", "queue_len")
        given = {key: getattr(self, key) for key in keys if getattr(self, key) is not None}
        return {**given, "num_tasks": self.num_tasks}


def export_format(output: str | Path) -> str:
    """The format of an output path: ``torchscript`` (``.pt``) or ``onnx`` (``.onnx``).

    Raises:
        ConfigError: Any other suffix (the message lists the valid ones).
    """
    suffix = Path(output).suffix
    if suffix not in FORMATS:
        raise ConfigError(
            f"output must end in .pt (TorchScript) or .onnx (ONNX), got {str(output)!r}"
        )
    return FORMATS[suffix]


def _example_inputs(actor: Actor) -> tuple[torch.Tensor, ...]:
    """Made-up inputs of the tracing sizes (values are irrelevant to a trace)."""
    gen = torch.Generator().manual_seed(0)
    out = []
    for spec in input_spec(actor.in_keys):
        shape = [_TRACE.get(dim, dim) for dim in spec["shape"]]
        if spec["name"] == "action_mask":
            mask = torch.ones(shape, dtype=torch.bool)
            mask[0, -1] = False
            out.append(mask)
        else:
            out.append(torch.rand(shape, generator=gen))
    return tuple(out)


@contextmanager
def _quiet_exporter() -> Iterator[None]:
    """Silence the ONNX exporter's logging and warnings (torchvision's missing ops, its
    progress, deprecations inside torch.export): they are not the user's to act on."""
    logger = logging.getLogger("torch.onnx")
    level = logger.level
    logger.setLevel(logging.ERROR)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)
            warnings.simplefilter("ignore", FutureWarning)
            yield
    finally:
        logger.setLevel(level)


def _to_torchscript(module: MaskedActor, inputs: tuple[torch.Tensor, ...]) -> bytes:
    traced = torch.jit.trace(module, inputs, check_trace=False)
    buffer = io.BytesIO()
    torch.jit.save(traced, buffer)
    return buffer.getvalue()


def _to_onnx(module: MaskedActor, inputs: tuple[torch.Tensor, ...]) -> Any:
    """The ``onnx.ModelProto`` of ``module``, every named dimension dynamic."""
    dims = {name: torch.export.Dim(name, min=1) for name in DIMS}
    dynamic = {
        spec["name"]: {i: dims[d] for i, d in enumerate(spec["shape"]) if isinstance(d, str)}
        for spec in input_spec(module.in_keys)
    }
    with _quiet_exporter(), torch.no_grad():
        program = torch.onnx.export(
            module, inputs, input_names=list(module.in_keys), output_names=[OUTPUT["name"]],
            dynamic_shapes=dynamic, dynamo=True, verbose=False,
        )  # fmt: skip
    return program.model_proto


def load_exported(data: bytes, fmt: str) -> Runner:
    """A function ``{input name: array} -> logits array`` of an exported model's bytes
    (``fmt``: ``torchscript`` or ``onnx``), as a user would run it."""
    if fmt == "torchscript":
        module = torch.jit.load(io.BytesIO(data))

        def run_torchscript(inputs: Mapping[str, np.ndarray]) -> np.ndarray:
            tensors = {k: torch.from_numpy(np.asarray(v)) for k, v in inputs.items()}
            with torch.no_grad():
                return module(**tensors).numpy()

        return run_torchscript
    import onnxruntime

    options = onnxruntime.SessionOptions()
    options.intra_op_num_threads = 1
    session = onnxruntime.InferenceSession(data, options, providers=["CPUExecutionProvider"])
    return lambda inputs: session.run(None, {k: np.asarray(v) for k, v in inputs.items()})[0]


def export_policy(source: str | Path, config: ExportConfig) -> tuple[Path, CheckReport]:
    """Export a policy's actor, check it on a recorded episode, then write it.

    The output is held for the run (:func:`~rtaw_marl.utils.runs.claim_file`: another
    export to it is refused) and must not be one of the inputs.

    Args:
        source: A checkpoint path or a shipped policy name (as :func:`load_policy`).
        config: The output file and the checked episode.

    Returns:
        The written model's path and the check's report.

    Raises:
        ConfigError: Unknown policy, bad suffix, unwritable output or one in use, an
            output (or its ``.json``) that is the checkpoint or another input, a missing
            ``export`` extra, bad env arguments.
        ExportCheckError: The exported model disagrees with the policy (nothing written).
    """
    if not config.output:
        raise ConfigError("output=FILE.pt (TorchScript) or output=FILE.onnx (ONNX) is needed")
    fmt = export_format(config.output)
    if fmt == "onnx":
        _need_onnx()
    path = checkpoint_path(source)
    _check_not_inputs(config, path)
    sidecar = f"{Path(config.output).name}.json"
    with claim_file(config.output, siblings=(sidecar,)) as output:
        return _export(source, path, output, fmt, config)


def _export(
    source: str | Path, path: Path, output: Path, fmt: str, config: ExportConfig
) -> tuple[Path, CheckReport]:
    """The work of :func:`export_policy`, once its output is held."""
    policy = load_policy(path, name=str(source))
    env = config.env_args()
    inputs, actions = record_decisions(policy, env, config.seed)
    module, example = masked_actor(policy.net), _example_inputs(policy.net)
    proto = _to_onnx(module, example) if fmt == "onnx" else None
    data = _to_torchscript(module, example) if proto is None else proto.SerializeToString()
    report = check_exported(
        load_exported(data, fmt), policy.net, inputs, actions, config.atol, config.rtol,
        env={**env, "seed": config.seed},
    )  # fmt: skip
    if not report.ok:
        raise ExportCheckError(
            f"the exported {fmt} model disagrees with {source}: {report.summary()}; nothing written"
        )
    spec = specification(source, path, policy.net, fmt)
    text = json.dumps(spec, indent=1)
    # The checked bytes, with the specification embedded (TorchScript: an extra file).
    data = _to_torchscript_with(data, text) if proto is None else _with_metadata(proto, text)
    sidecar = json.dumps({**spec, "check": {**asdict(report), "ok": report.ok}}, indent=1)
    # The model and its specification land together: a stop waits for both.
    with signals_held():
        atomic_write(output, lambda fh: fh.write(data))
        atomic_write(Path(f"{output}.json"), lambda fh: fh.write(sidecar.encode()))
    return output, report


def _check_not_inputs(config: ExportConfig, checkpoint: Path) -> None:
    """Refuse an output, or its ``<output>.json``, that would replace an input: the
    checkpoint, or a layout or task file named by ``layout=`` or ``tasks=``.

    Files are compared by where they really are (symlinks, ``..`` and relative paths
    resolved), and by the name in the resolved folder (an atomic write replaces that
    name, which may be a symlink to the input).
    """
    inputs = {"the checkpoint being exported": checkpoint}
    for key in ("layout", "tasks"):
        value = getattr(config, key)
        if value is not None and os.path.isfile(value):
            inputs[f"the {key} file"] = Path(value)
    places = {place: (what, p) for what, p in inputs.items() for place in _places(p)}
    output = Path(config.output)
    for target in (output, Path(f"{output}.json")):
        hit = next((places[p] for p in _places(target) if p in places), None)
        if hit is None:
            continue
        what, path = hit
        written = "the model" if target == output else f"its specification {target.name}"
        raise ConfigError(
            f"output={config.output}: {written} would replace {what} ({path}); "
            "choose another output file"
        )


def _places(path: Path) -> set[str]:
    """Where ``path`` is: the file it resolves to, and the name in its resolved folder."""
    return {os.path.realpath(path), os.path.join(os.path.realpath(path.parent), path.name)}


def _need_onnx() -> None:
    """Refuse ``.onnx`` in one line when the ``export`` extra is not installed."""
    for module in EXTRAS["export"]:
        if importlib.util.find_spec(module) is None:
            raise ConfigError(extra_message("output=*.onnx", "export", module))


def specification(source: str | Path, path: Path, actor: Actor, fmt: str) -> dict[str, Any]:
    """The description of an exported model: format, model, source, inputs, output."""
    ckpt = load_checkpoint(path)
    model = dict(ckpt["model_config"])
    return {
        "format": EXPORT_FORMAT,
        "model_format": fmt,
        "model": model.get("name", "rtaw"),
        "model_config": model,
        "source": {
            "policy": str(source),
            "file": str(path),
            "sha256": hashlib.sha256(path.read_bytes()).hexdigest(),
            "frames": ckpt.get("frames"),
        },
        "dims": DIMS,
        "normalisation": NORMALISATION,
        "inputs": input_spec(actor.in_keys),
        "output": OUTPUT,
        "versions": library_versions(),
    }


def _to_torchscript_with(data: bytes, text: str) -> bytes:
    """The TorchScript bytes with the specification as the extra file ``SPEC_NAME``."""
    buffer = io.BytesIO()
    torch.jit.save(torch.jit.load(io.BytesIO(data)), buffer, _extra_files={SPEC_NAME: text})
    return buffer.getvalue()


def _with_metadata(proto: Any, text: str) -> bytes:
    """The ONNX model with the specification as metadata ``SPEC_NAME`` and each input's
    meaning as its ``doc_string``."""
    spec = json.loads(text)
    meanings = {item["name"]: item["meaning"] for item in spec["inputs"]}
    for node in proto.graph.input:
        node.doc_string = meanings.get(node.name, "")
    proto.doc_string = f"rtaw_marl actor ({spec['model']}) of {spec['source']['policy']}"
    entry = proto.metadata_props.add()
    entry.key, entry.value = SPEC_NAME, text
    return proto.SerializeToString()
