"""Regenerate the env spec pages from the env modules' docstrings.

* docs/environment.md: :mod:`rtaw_marl.envs.pettingzoo` (the PettingZoo AEC env), then a
  hand-written "Integrations" block (:data:`INTEGRATIONS`);
* docs/gymnasium.md: :mod:`rtaw_marl.envs.gymnasium` (the single-agent adapter).

Usage: ``python -m benchmarks.scripts.gen_env_doc`` (``--check`` exits 1 if a page is stale).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from types import ModuleType

import rtaw_marl.envs.gymnasium as gymnasium_env
import rtaw_marl.envs.pettingzoo as warehouse

DOCS = Path(__file__).resolve().parents[2] / "docs"

#: Appended to docs/environment.md: the library table lives in docs/integrations.md.
INTEGRATIONS = """
## Integrations

Tianshou and TorchRL take this env as it is (for TorchRL beyond a few dozen robots,
`rtaw_marl.envs.torchrl_wrapper.WarehouseWrapper`: its `PettingZooWrapper` filling every
robot's row at once, from `observe_all()`); Stable-Baselines3 (SB3-contrib's
`MaskablePPO`) and other single-agent libraries take the Gymnasium adapter
`rtaw/warehouse-single-v1` ([gymnasium.md](gymnasium.md)), which returns each decision's own
reward; SuperSuit's Box wrappers apply to the flat layout. There is no parallel version:
robots act at irregular times, so PettingZoo's `aec_to_parallel` refuses the env.
Versions tested, snippets and known limits: [integrations.md](integrations.md).
"""

#: Page name -> (module whose docstring it is, hand-written block after it).
PAGES: dict[str, tuple[ModuleType, str]] = {
    "environment.md": (warehouse, INTEGRATIONS),
    "gymnasium.md": (gymnasium_env, ""),
}


def render(module: ModuleType, extra: str = "") -> str:
    """The markdown page: the module docstring under a generation notice, then ``extra``."""
    source = "/".join(module.__name__.split(".")) + ".py"
    header = f"<!-- Generated from {source} by benchmarks/scripts/gen_env_doc.py -->\n\n"
    return header + (module.__doc__ or "").strip() + "\n" + extra


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--check", action="store_true", help="fail if a page is stale")
    args = parser.parse_args()
    stale = []
    for name, (module, extra) in PAGES.items():
        doc, text = DOCS / name, render(module, extra)
        if args.check:
            if not doc.is_file() or doc.read_text() != text:
                stale.append(str(doc))
            continue
        doc.write_text(text)
        print(f"wrote {doc}")
    if stale:
        print(
            f"stale: {', '.join(stale)}; run python -m benchmarks.scripts.gen_env_doc",
            file=sys.stderr,
        )
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
