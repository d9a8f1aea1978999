"""``python -m rtaw_marl``: the version, what the package is, its commands with the extra
each needs, and where the documentation is. ``--version`` prints the version alone.

Standard library only (the commands come from :mod:`rtaw_marl.utils.commands`), so it
answers on an install without any extra.
"""

from __future__ import annotations

import sys

import rtaw_marl
from rtaw_marl.errors import did_you_mean
from rtaw_marl.utils.commands import NEEDS, SUMMARIES

__all__ = ["main", "overview"]

#: What the error suggests for a misspelt option (``-h`` is ``--help`` too).
_OPTIONS = ("--version", "--help")


def _description() -> str:
    # The package docstring's first line, "rtaw_marl: <what it is>."; empty under
    # ``python -OO``, which strips docstrings.
    first = (rtaw_marl.__doc__ or "").strip().partition("\n")[0]
    return first.removeprefix("rtaw_marl:").strip().rstrip(".")


def overview() -> str:
    """The text ``python -m rtaw_marl`` prints: version, description, commands, docs."""
    description = _description()
    lines = [f"rtaw_marl {rtaw_marl.__version__}" + (f": {description}" if description else "")]
    lines += [
        "",
        "Python: from rtaw_marl import warehouse_v1 (the PettingZoo env; no extra needed)",
        "",
        "Commands, with the extra each needs (pip install 'rtaw_marl[EXTRA]'):",
    ]
    width = max(len(f"rtaw-{command}") for command in SUMMARIES)
    extra_width = max(len(extra) for extra, _ in NEEDS.values())
    for command, summary in SUMMARIES.items():
        extra = NEEDS[command][0]
        lines.append(f"  {f'rtaw-{command}':<{width}}  {extra:<{extra_width}}  {summary}")
    lines += [
        "Trained policies (policy=pretrained, policy=checkpoint) also need the train extra.",
        "",
        "Options of a command: rtaw-<command> --help.",
        "Documentation: README.md and docs/index.md in the source repository.",
    ]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    """Print the overview (no argument, ``-h``, ``--help``) or the version (``--version``).

    Args:
        argv: The arguments; ``sys.argv[1:]`` when ``None``.

    Returns:
        The exit status: 0, or 2 after one ``error: ...`` line on stderr for any other
        argument.
    """
    args = sys.argv[1:] if argv is None else argv
    if not args or args in (["-h"], ["--help"]):
        print(overview())
        return 0
    if args == ["--version"]:
        print(rtaw_marl.__version__)
        return 0
    given = " ".join(args)
    hint = did_you_mean(args[0], _OPTIONS) if len(args) == 1 else ""
    print(
        f"error: unknown argument {given!r}: python -m rtaw_marl takes no argument, "
        f"--version or --help{hint}",
        file=sys.stderr,
    )
    return 2


if __name__ == "__main__":
    sys.exit(main())
