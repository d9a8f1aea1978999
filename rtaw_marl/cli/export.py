"""``rtaw-export``: a trained policy's actor as a TorchScript or ONNX file, checked.

Examples::

    rtaw-export generalist_plus output=generalist_plus.onnx
    rtaw-export A_astar_m10 output=rtaw_A.pt layout=A num_robots=30 queue_len=20
    rtaw-export runs/demo/checkpoints/best.pt output=best.onnx scenario=C_astar_m10

``POLICY`` is a shipped name or a checkpoint path; the ``KEY=VALUE`` options are the
fields of :class:`~rtaw_marl.policies.export.ExportConfig`. The model is written only
after it chose as the Python policy at every decision of a checked episode, with its
specification beside it (``<output>.json``; docs/export.md); the output is held for the
run (another export to it is refused). A user error (unknown policy or key, bad suffix
or value, a tolerance out of its range, an output that would replace the checkpoint) is
one ``error:`` line and exit status 2, before any work; an export that disagrees with
the policy is one line and exit status 1, and writes nothing.
"""

from __future__ import annotations

import argparse
import dataclasses
from typing import Any

from rtaw_marl.cli.plain import OneLineParser, exit_after
from rtaw_marl.errors import ConfigError
from rtaw_marl.policies.export import ExportCheckError, ExportConfig, export_policy

__all__ = ["main", "parse", "parser", "run"]

#: ExportConfig key -> how its value is read (``none`` or ``null`` is ``None``).
_KINDS: dict[str, type] = {
    "num_robots": int, "queue_len": int, "num_tasks": int, "seed": int,
    "atol": float, "rtol": float,
}  # fmt: skip


def parser() -> argparse.ArgumentParser:
    """The command line of ``rtaw-export``."""
    keys = ", ".join(f.name for f in dataclasses.fields(ExportConfig))
    p = OneLineParser(
        prog="rtaw-export",
        description=(__doc__ or "").splitlines()[0],
        epilog=f"keys: {keys} (docs/export.md)",
    )
    p.add_argument("policy", help="a shipped policy name or a checkpoint path")
    p.add_argument("options", nargs="*", metavar="KEY=VALUE", help="output=FILE.pt|FILE.onnx ...")
    return p


def parse(options: list[str]) -> ExportConfig:
    """``KEY=VALUE`` strings -> the typed config.

    Raises:
        ConfigError: An option without ``=``, an unknown key (the valid ones listed), a
            key given twice, a value of the wrong type, or a tolerance out of its range
            (:func:`~rtaw_marl.policies.export.check_tolerance`).
    """
    valid = [f.name for f in dataclasses.fields(ExportConfig)]
    values: dict[str, Any] = {}
    for option in options:
        key, sep, text = option.partition("=")
        if not sep:
            raise ConfigError(f"expected KEY=VALUE, got {option!r}; keys: {', '.join(valid)}")
        if key not in valid:
            raise ConfigError(f"unknown key {key!r}; valid keys: {', '.join(valid)}")
        if key in values:
            raise ConfigError(f"{key} is given twice")
        values[key] = _value(key, text)
    return ExportConfig(**values)


def _value(key: str, text: str) -> Any:
    default = next(f.default for f in dataclasses.fields(ExportConfig) if f.name == key)
    if text.lower() in ("none", "null") and default is None:
        return None
    kind = _KINDS.get(key, str)
    try:
        value = kind(text)
    except ValueError:
        name = "an integer" if kind is int else "a number"
        raise ConfigError(f"{key} must be {name}, got {text!r}") from None
    if kind is int and key != "seed" and value < 1:
        raise ConfigError(f"{key} must be an integer >= 1, got {text!r}")
    if key == "seed" and value < 0:
        raise ConfigError(f"{key} must be >= 0, got {text!r}")
    # atol and rtol: ExportConfig checks their range, for the Python API too.
    return value


def run(argv: list[str] | None = None) -> int:
    """Run ``rtaw-export`` with ``argv``; returns the exit status.

    Raises:
        RtawError: A user error (see :func:`parse` and
            :func:`~rtaw_marl.policies.export.export_policy`).
    """
    args = parser().parse_args(argv)
    config = parse(args.options)
    path, report = export_policy(args.policy, config)
    print(f"{args.policy} -> {path} (specification: {path}.json)")
    print(f"checked: {report.summary()}")
    return 0


def main(argv: list[str] | None = None) -> None:
    """Console entry point: user errors are one ``error:`` line and exit status 2, an
    export that disagrees with the Python policy exit status 1."""
    exit_after(run, argv, failures=(ExportCheckError,))


if __name__ == "__main__":
    main()
