"""The maps shipped inside the package, and the ``builtin:NAME`` path syntax.

``rtaw_marl/maps/`` holds a few small public maps, copied byte-for-byte with their
licenses (its ``README.md`` gives each file's size, source repository and commit): the
original RTAW code's six 64x64 layouts, one MovingAI warehouse, and a League of Robot
Runners problem with its map, agent and task files (kept in upstream's relative layout,
so the paths inside the JSON resolve).

Wherever a layout, task or problem file is expected (``layout.path``, ``tasks.path``,
``layout.problem``, ``tasks.problem``, ``rtaw-lorr problem=``, the same keys given to
``warehouse_v1.env``), ``builtin:NAME`` names one of :data:`MAPS` instead of a path::

    rtaw-eval layout=file layout.path=builtin:usc_64.cfg policy=mpdm
    rtaw-eval scenario=lorr tasks.problem=builtin:random_32_32_20_100.json

Every reader resolves its argument through :func:`resolve_path`, so the syntax works the
same everywhere; any other string is an ordinary path, used exactly as given (a file
really named ``builtin:x`` is reachable as ``./builtin:x``). No path falls back to a
shipped map: an unknown name is an error listing the valid ones.

Stdlib only: the env-only install and ``import rtaw_marl.sim`` stay light.
"""

from __future__ import annotations

from collections.abc import Mapping
from os import PathLike
from pathlib import Path
from types import MappingProxyType

from rtaw_marl.errors import unknown_name

__all__ = ["BUILTIN", "MAPS", "MAPS_DIR", "map_path", "resolve_path"]

#: The prefix that names a shipped map instead of a path.
BUILTIN = "builtin:"

#: The shipped maps' folder (``rtaw_marl/maps/``, package data of the wheel).
MAPS_DIR = Path(__file__).resolve().parents[1] / "maps"

#: Every name ``builtin:NAME`` accepts -> its file, relative to :data:`MAPS_DIR`. The
#: LoRR problem's agent and task files are not listed: they are read through its JSON.
MAPS: Mapping[str, str] = MappingProxyType(
    {
        **{
            f"{stem}.cfg": f"rtaw/{stem}.cfg"
            for stem in (
                "open_64",
                "usc_64",
                "tight_64",
                "tight_2_64",
                "compact_64",
                "compact_2_64",
            )
        },
        "warehouse-10-20-10-2-1.map": "movingai/warehouse-10-20-10-2-1.map",
        "random_32_32_20_100.json": "lorr/random_32_32_20_100.json",
        "random-32-32-20.map": "lorr/maps/random-32-32-20.map",
    }
)


def map_path(name: str) -> Path:
    """The file of the shipped map ``name`` (a key of :data:`MAPS`, e.g. ``usc_64.cfg``).

    Raises:
        ConfigError: ``name`` is not a shipped map; the message lists the valid names.
    """
    if name not in MAPS:
        raise unknown_name("builtin map", name, list(MAPS))
    return MAPS_DIR / MAPS[name]


def resolve_path(path: str | PathLike[str]) -> Path:
    """The file an input path names: ``builtin:NAME`` -> :func:`map_path` ``(NAME)``;
    anything else -> ``Path(path)``, unchanged (neither made absolute nor checked, so
    the caller's own "not found" message stays as it was).

    Only a ``str`` carries the syntax: a :class:`~pathlib.Path` is always a path.

    Raises:
        ConfigError: ``path`` is ``builtin:`` with an unknown name (listing the valid ones).
    """
    if isinstance(path, str) and path.startswith(BUILTIN):
        return map_path(path[len(BUILTIN) :])
    return Path(path)
