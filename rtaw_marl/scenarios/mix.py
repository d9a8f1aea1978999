"""Scenario mixes: the settings one generalist policy trains on at once (``mix=``).

A member is a registered scenario name, optionally with keys changed, each after a
colon: ``m<M>`` robots, ``n<N>`` queue slots, ``t<T>`` tasks per episode, ``paper`` or
``drain`` episodes, ``s<S>`` the scenario's generated layout at ``S x S`` cells (a map
read from a file has no size to change), ``random`` or ``designated`` tasks.
``C_astar_m10:m30:n5:paper`` is layout C with 30 robots, a queue of 5 and ``paper``
episodes; ``A_astar_m10:s90:random`` layout A generated at 90x90 with random tasks; the
syntax needs no quoting on Hydra's command line (``mix=[C_astar_m10,C_astar_m10:m30:n5]``).
Each member gets its own simulators in every collector's batch
(:class:`~rtaw_marl.envs.mixed.MixedBatchedEnv`), so one batch holds many fleets, queues
and maps.

:data:`GENERALIST` is the shipped generalist's mix: every Table I layout (open grid and
layouts A-E, 60x60) at robot counts from 5 to 200, a 256x256 warehouse and a 300x300
open grid at 500 and 1,000 robots, queues of 5 and 10, both episode modes. It leaves
out what the generalist is evaluated on as unseen: robot counts 30, 150, 300, 2,000 and
above, queues of 20, the MovingAI maps and LoRR's ``warehouse_large``. (A member with
a longer queue pads every row of the batch to it: a queue of 20 doubled the cost of
the update, so none is trained on.)
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

from rtaw_marl.errors import ConfigError, LayoutError
from rtaw_marl.scenarios.registry import Scenario, scenario
from rtaw_marl.sim.builder import SimSpec

__all__ = ["GENERALIST", "MEMBER_KEYS", "member_spec", "mix_specs"]

#: A member's key prefixes and the simulator key each sets (plus ``paper``/``drain``,
#: ``s<S>``, ``random``/``designated``: the module docstring).
MEMBER_KEYS = {"m": "num_robots", "n": "queue_len", "t": "num_tasks"}
#: The generated layouts ``s<S>`` can resize (the others are read from files).
SIZED_LAYOUTS = ("open", "shelves", "A", "B", "C", "D", "E")
#: The task streams a member can switch to.
MEMBER_STREAMS = ("random", "designated")

#: The shipped generalist's training mix (module docstring).
GENERALIST: tuple[str, ...] = (
    "open60_direct_m10:m5",
    "A_astar_m10",
    "B_astar_m10:m20:n5",
    "C_astar_m10:paper",
    "D_astar_m10:m50",
    "E_astar_m100:n5",
    "open60_direct_m100:paper",
    "A_astar_m100:m200:paper",
    "C_astar_m100",
    "B_astar_m10:m15:paper",
    "D_astar_m100:m70:n5",
    "E_astar_m10:m8",
    "C256_astar_m500_random",
    "open300_direct_m1000_random",
    "open300_direct_m500_random:t2500",
    "C256_astar_m1000_random:t2500",
)


def member_spec(member: str) -> SimSpec:
    """The simulator spec of one mix member (module docstring for the syntax).

    Raises:
        ConfigError: An unknown scenario (the message lists them), key or value.
    """
    name, *keys = str(member).split(":")
    base = scenario(name.strip())
    sim: dict[str, object] = {}
    sized = False
    for key in keys:
        if key in ("paper", "drain"):
            sim["episode_mode"] = key
        elif key in MEMBER_STREAMS:
            base = dataclasses.replace(base, tasks=key)
        elif key[:1] == "s" and key[1:].isdigit():
            base = _resized(base, int(key[1:]), member)
            sized = True
        elif key[:1] in MEMBER_KEYS and key[1:].isdigit():
            sim[MEMBER_KEYS[key[0]]] = int(key[1:])
        else:
            raise ConfigError(
                f"mix member {member!r}: {key!r} is not m<robots>, n<queue slots>, "
                "t<tasks>, s<layout size>, paper, drain, random or designated"
            )
    spec = base.with_sim(**sim).spec()
    if sized:  # a size its shelves do not fit is an error here, not in a collector
        try:
            spec.layout.build()
        except LayoutError as err:
            raise ConfigError(f"mix member {member!r}: {err}") from None
    return spec


def _resized(base: Scenario, size: int, member: str) -> Scenario:
    """``base`` with its generated layout at ``size x size`` cells."""
    layout, keys = base.choice("layout")
    if layout not in SIZED_LAYOUTS:
        raise ConfigError(
            f"mix member {member!r}: s<size> resizes a generated layout "
            f"({', '.join(SIZED_LAYOUTS)}); {base.name}'s layout is {layout!r}"
        )
    return dataclasses.replace(base, layout={"name": layout, **keys, "width": size, "height": size})


def mix_specs(members: Sequence[str]) -> list[SimSpec]:
    """The specs of a mix's members, in order.

    Raises:
        ConfigError: A member is given twice, or is invalid (:func:`member_spec`).
    """
    members = list(members)
    if len(set(members)) < len(members):
        twice = sorted({m for m in members if members.count(m) > 1})
        raise ConfigError(f"mix lists {twice} more than once; list each member once")
    return [member_spec(m) for m in members]
