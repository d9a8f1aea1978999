"""The written specification of an exported actor's inputs and output (``rtaw-export``).

Every input tensor of the exported RTAW (``model=rtaw``) and RTAW+ (``model=rtaw_plus``)
actors is one entry of the ``warehouse_v1`` observation, with a leading batch axis: its
columns are those of :mod:`rtaw_marl.decision.features` (the one observation builder), and
their meaning, unit and range are written once here, in :data:`COLUMNS`. The sidecar
JSON of an export, the metadata embedded in the exported file and ``docs/export.md`` are
made from :func:`input_spec`. Plain Python: no torch.
"""

from __future__ import annotations

from typing import Any

from rtaw_marl.decision.features import (
    MISSING,
    NUM_RIVALS,
    RELATION_FEATURES,
    RIVAL_FEATURES,
    ROBOT_FEATURES,
    SOFTMIN_TEMPERATURE,
    TASK_FEATURES,
)

__all__ = ["COLUMNS", "DIMS", "INPUTS", "NORMALISATION", "OUTPUT", "input_spec"]

#: Every dimension name of the exported tensors.
DIMS = {
    "batch": "decisions scored at once (1 for one decision; any number)",
    "tasks": "N, the queue slots (the env's queue_len; any number >= 1)",
    "robots": "M, the robots of the fleet (any number >= 1)",
}

NORMALISATION = (
    "Every length and time is divided by the layout scale L = max(W, H) of the grid "
    "(cells; robots move one cell per second, so a time in seconds and a distance in "
    "cells share the unit), computed in float64 and stored as float32. Distances are "
    "the navigator's: Euclidean for navigator=direct, 4-connected shortest paths for "
    "astar, sipp, cbs. Coordinates: x = column, y = row. Empty queue slots are all zeros."
)

_POS, _TIME = "cells / L", "s / L"
_ARRIVAL = "time until free + distance to the origin; the acting robot's: its distance k"
_ROBOT = {
    "x": ("column of the cell where the robot is next free", _POS, "[0, 1]"),
    "y": ("row of the cell where the robot is next free", _POS, "[0, 1]"),
    "time_until_free": ("time until the robot is free (0 for the acting one)", _TIME, ">= 0"),
}
_NTH = {1: "1st", 2: "2nd", 3: "3rd"}
#: Input name -> column name -> (meaning, unit, range), every column of every input.
COLUMNS: dict[str, dict[str, tuple[str, str, str]]] = {
    "robots": _ROBOT,
    "agent": _ROBOT,
    "tasks": {
        "ox": ("column of the task's origin (pickup)", _POS, "[0, 1]"),
        "oy": ("row of the task's origin", _POS, "[0, 1]"),
        "dx": ("column of the task's destination (delivery)", _POS, "[0, 1]"),
        "dy": ("row of the task's destination", _POS, "[0, 1]"),
        "distance_to_origin": ("distance k from the acting robot to the origin", _POS, ">= 0"),
        "length": ("task length, origin -> destination", _POS, ">= 0"),
    },
    "relations": {
        "distance": ("distance k from the acting robot to the origin", _POS, ">= 0"),
        "length": ("task length, origin -> destination", _POS, ">= 0"),
        "wait": ("time the task has waited in the queue", _TIME, ">= 0"),
        **{
            f"rival_{i}": (
                f"arrival of the {_NTH[i]}-fastest other robot ({_ARRIVAL}) minus k; "
                f"{MISSING} when there are fewer other robots",
                _TIME,
                "any (< 0: that rival arrives first)",
            )
            for i in (1, 2, 3)
        },
        "rival_softmin": (
            f"soft-min (temperature {SOFTMIN_TEMPERATURE} L) of every other robot's "
            f"arrival, minus k; {MISSING} without other robots",
            _TIME,
            "any",
        ),
        "chain": (
            f"distance from the destination to the nearest other queued origin; {MISSING} "
            "when no other task is queued",
            _POS,
            ">= 0",
        ),
    },
    "rivals": {
        "arrival_minus_k": (f"the rival's arrival ({_ARRIVAL}) minus k", _TIME, "any"),
        "time_until_free": ("the rival's time until free", _TIME, ">= 0"),
        "distance": ("distance from the rival's next free cell to the origin", _POS, ">= 0"),
        "valid": ("1 for a rival, 0 for a padding row (fewer than 9 robots)", "flag", "{0, 1}"),
    },
    "action_mask": {},
}

#: Input name -> (dimension names and sizes, columns, observation key, what it is).
INPUTS: dict[str, tuple[tuple[str | int, ...], tuple[str, ...], str]] = {
    "robots": (
        ("batch", "robots", len(ROBOT_FEATURES)),
        ROBOT_FEATURES,
        "every robot's row (observation='full' only)",
    ),
    "tasks": (
        ("batch", "tasks", len(TASK_FEATURES)),
        TASK_FEATURES,
        "every queue slot seen by the acting robot",
    ),
    "agent": (("batch", len(ROBOT_FEATURES)), ROBOT_FEATURES, "the acting robot's row of robots"),
    "relations": (
        ("batch", "tasks", len(RELATION_FEATURES)),
        RELATION_FEATURES,
        "every queue slot relative to the acting robot and its rivals",
    ),
    "rivals": (
        ("batch", "tasks", NUM_RIVALS, len(RIVAL_FEATURES)),
        RIVAL_FEATURES,
        f"per slot, the {NUM_RIVALS} other robots arriving first, sorted by arrival "
        "(ties: lowest robot id)",
    ),
    "action_mask": (("batch", "tasks"), (), "true for the slots holding a task"),
}

OUTPUT = {
    "name": "logits",
    "dtype": "float32",
    "shape": ["batch", "tasks"],
    "meaning": (
        "one score per queue slot, -inf where action_mask is false; the policy's action "
        "is the argmax (the first slot on a tie), as load_policy(...).act(obs) chooses"
    ),
}


def input_spec(in_keys: tuple[str, ...]) -> list[dict[str, Any]]:
    """The specification of an actor's inputs, in its argument order.

    Args:
        in_keys: The actor's ``in_keys`` (``action_mask`` last).

    Returns:
        One dict per input: ``name``, ``dtype``, ``shape`` (dimension names and fixed
        sizes), ``observation`` (where ``obs`` of ``warehouse_v1`` holds it),
        ``meaning`` and ``columns`` (name, meaning, unit, range of each last-axis column).
    """
    out = []
    for key in in_keys:
        shape, columns, meaning = INPUTS[key]
        where = (
            'obs["action_mask"].astype(bool)'
            if key == "action_mask"
            else f'obs["observation"]["{key}"]'
        )
        out.append(
            {
                "name": key,
                "dtype": "bool" if key == "action_mask" else "float32",
                "shape": list(shape),
                "observation": where,
                "meaning": meaning,
                "columns": [
                    dict(
                        zip(
                            ("name", "meaning", "unit", "range"), (c, *COLUMNS[key][c]), strict=True
                        )
                    )
                    for c in columns
                ],
            }
        )
    return out
