"""Regenerate docs/environment.md from the env module's docstring (its spec page).

Usage: ``python experiments/gen_env_doc.py`` (``--check`` exits 1 if the file is stale).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import rtaw_marl.envs.pettingzoo as warehouse

DOC = Path(__file__).resolve().parents[1] / "docs" / "environment.md"
HEADER = "<!-- Generated from rtaw_marl/envs/pettingzoo.py by experiments/gen_env_doc.py -->\n\n"


def render() -> str:
    """The markdown page: the module docstring under a generation notice."""
    return HEADER + (warehouse.__doc__ or "").strip() + "\n"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--check", action="store_true", help="fail if docs/environment.md is stale")
    args = parser.parse_args()
    text = render()
    if args.check:
        if not DOC.is_file() or DOC.read_text() != text:
            print(f"{DOC} is stale; run python experiments/gen_env_doc.py", file=sys.stderr)
            return 1
        return 0
    DOC.write_text(text)
    print(f"wrote {DOC}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
