"""The scenario registry's YAML twins: ``conf/scenario/<name>.yaml`` and ``conf/row/<row>.yaml``.

Both folders are generated from :data:`~rtaw_marl.scenarios.SCENARIOS` and
:data:`~rtaw_marl.scenarios.ROWS`, so a setting is written once (the test suite fails when
a file drifts). Regenerate them after changing the registry::

    python -m rtaw_marl.scenarios.configs
"""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Any

from rtaw_marl.scenarios.lorr import lorr_yaml
from rtaw_marl.scenarios.registry import ROWS, SCENARIOS, Scenario
from rtaw_marl.utils.atomic import atomic_write

__all__ = ["CONF_DIR", "expected_files", "row_yaml", "scenario_yaml", "write_configs"]

CONF_DIR = Path(__file__).resolve().parents[1] / "conf"
_GENERATED = (
    "# Generated from rtaw_marl.scenarios (python -m rtaw_marl.scenarios.configs); do not edit."
)


def scenario_yaml(s: Scenario) -> str:
    """The ``scenario=<name>`` config: its groups and the keys it sets.

    ``scenario=default`` sets nothing: each command's own defaults are the default
    scenario (``rtaw-render`` keeps its SIPP execution); the tests check that
    ``rtaw-eval`` and ``rtaw-train`` then build :data:`SCENARIOS` ``["default"]``.
    """
    if s.name == "default":
        return "\n".join(["# @package _global_", f"# {s.description}.", _GENERATED]) + "\n"
    lines = ["# @package _global_", f"# {s.description}.", _GENERATED, "defaults:"]
    blocks: list[str] = []
    for group in ("layout", "navigator", "tasks"):
        name, keys = s.choice(group)
        lines.append(f"  - override /{group}: {name}")
        blocks += _block(group, keys)
    blocks = _block("env", dict(s.env)) + blocks
    return "\n".join([*lines, *blocks]) + "\n"


def row_yaml(row: str) -> str:
    """The ``row=<row>`` config: a Table I row's scenario and its shipped policies."""
    s = SCENARIOS[ROWS[row]]
    labels = ", ".join(s.policies)
    return (
        "\n".join(
            [
                "# @package _global_",
                f"# Table I row {s.title!r}: scenario {s.name} and its shipped policies "
                f"({labels}).",
                _GENERATED,
                "defaults:",
                f"  - override /scenario: {s.name}",
                "",
                f"pretrained: {_flow(list(s.policies.values()))}",
            ]
        )
        + "\n"
    )


def expected_files(conf_dir: Path = CONF_DIR) -> dict[Path, str]:
    """Every generated file and its text."""
    files = {
        conf_dir / "scenario" / f"{name}.yaml": scenario_yaml(s) for name, s in SCENARIOS.items()
    }
    files.update({conf_dir / "row" / f"{row}.yaml": row_yaml(row) for row in ROWS})
    files[conf_dir / "scenario" / "lorr.yaml"] = lorr_yaml()
    return files


def write_configs(conf_dir: Path = CONF_DIR) -> list[Path]:
    """Write the generated files and remove stale ones; returns the files that changed."""
    files = expected_files(conf_dir)
    changed = []
    for folder in ("scenario", "row"):
        for stale in sorted((conf_dir / folder).glob("*.yaml")):
            if stale not in files:
                stale.unlink()
                changed.append(stale)
    for path, text in files.items():
        if not path.is_file() or path.read_text() != text:
            path.parent.mkdir(parents=True, exist_ok=True)
            atomic_write(path, lambda fh, text=text: fh.write(text.encode()))
            changed.append(path)
    return changed


def _block(group: str, keys: dict[str, Any]) -> list[str]:
    if not keys:
        return []
    return ["", f"{group}:", *(f"  {k}: {_flow(v)}" for k, v in keys.items())]


def _flow(value: Any) -> str:
    """A YAML flow value (JSON is YAML); names stay unquoted, as in the other twins."""
    if isinstance(value, list):
        return "[" + ", ".join(_flow(v) for v in value) + "]"
    if isinstance(value, str) and value.replace("_", "").isalnum():
        return value
    return json.dumps(value)


if __name__ == "__main__":
    for path in write_configs():
        print(f"wrote {path}")
    sys.exit(0)
