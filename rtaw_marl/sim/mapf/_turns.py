"""Compiled kernel of lifelong PIBT with LoRR's action model: headings and quarter turns.

In the League of Robot Runners (LoRR) a robot faces east, south, west or north, and each
timestep it moves one cell forward (``F``), turns a quarter clockwise (``R``) or
counter-clockwise (``C``), or waits (``W``). LoRR's start kit plans with PIBT on cells
and turns that into actions (``default_planner/planner.cpp``, ``pibt.cpp``); this kernel
does the same, in the same three stages:

1. **Commitments.** A robot that chose a next cell keeps it until it is there (it may
   need turns first): its cell is reserved before anyone else plans.
2. **PIBT** (:func:`~rtaw_marl.sim.mapf._pibt.pibt_plan`) for the uncommitted robots,
   in priority order; a committed robot is never pushed, and no robot enters the cell
   of one committed to its own (a swap). Among cells equally near its goal a robot
   prefers the one it faces (no turn), as the kit's ``causalPIBT``: random tie-breaks
   alone would turn it back and forth on every staircase path.
3. **Actions.** A robot facing its next cell moves forward; otherwise it turns toward
   it (clockwise for a half turn, as the kit). A forward move into a cell whose robot
   does not itself move forward is cancelled (``moveCheck``): the robot waits, and so
   does every robot behind it.

The result has no vertex or swap conflicts: a cell is entered only when its robot
leaves it forward in the same timestep (a chain, or a cycle of three or more).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from rtaw_marl.sim.mapf._pibt import pibt_plan

__all__ = ["FORWARD", "TURN_CCW", "TURN_CW", "WAIT", "turn_step"]

#: Action codes, LoRR's letters ``F``, ``R``, ``C``, ``W``.
FORWARD, TURN_CW, TURN_CCW, WAIT = 0, 1, 2, 3
#: LoRR's heading (0 east, 1 south, 2 west, 3 north) of each of ``nbr``'s four columns
#: (``+x``, ``-x``, ``+y``, ``-y``: rows grow southwards). A swap of two pairs, so it is
#: its own inverse: ``_HEADING_OF[h]`` is also the column in front of heading ``h``.
_HEADING_OF = np.array([0, 2, 1, 3], dtype=np.int64)
#: The tie-break of the cell a robot faces: below every other (they are in ``[0, 1)``).
_PREFER_AHEAD = -0.5


@njit(cache=True, nogil=True)
def _action(pos: int, nxt: int, heading: int, nbr: np.ndarray) -> int:
    """The action that takes a robot at ``pos`` facing ``heading`` toward ``nxt``."""
    if nxt == pos:
        return WAIT
    want = -1
    for k in range(4):
        if nbr[pos, k] == nxt:
            want = _HEADING_OF[k]
    if want == heading:
        return FORWARD
    if want == (heading + 3) % 4:
        return TURN_CCW
    return TURN_CW  # a quarter clockwise, or the first of a half turn


@njit(cache=True, nogil=True)
def _cancel_blocked(pos, target, action, occ_now, checked, chain) -> None:
    """Cancel every forward move into a cell whose robot does not move forward too, and
    every move behind it (LoRR kit's ``moveCheck``, without recursion)."""
    m = pos.shape[0]
    checked[:] = False
    for start in range(m):
        if checked[start] or action[start] != FORWARD:
            continue
        # Follow the chain of robots ahead until a free cell, a robot not moving
        # forward, or one already checked (moving forward: fine, as on a cycle).
        length, i, ok = 0, start, True
        while True:
            if checked[i]:
                ok = action[i] == FORWARD
                break
            checked[i] = True
            chain[length] = i
            length += 1
            if action[i] != FORWARD:
                ok = False
                break
            ahead = occ_now[target[i]]
            if ahead < 0:
                break
            i = ahead
        if not ok:
            for k in range(length):
                if action[chain[k]] == FORWARD:
                    action[chain[k]] = WAIT


@njit(cache=True, nogil=True)
def turn_step(
    pos: np.ndarray,
    heading: np.ndarray,
    target: np.ndarray,
    order: np.ndarray,
    goal_field: np.ndarray,
    fields: np.ndarray,
    nbr: np.ndarray,
    tie: np.ndarray,
    occ_now: np.ndarray,
    occ_next: np.ndarray,
    nxt: np.ndarray,
    action: np.ndarray,
) -> None:
    """Plan and apply one timestep with headings (module docstring).

    Args:
        pos: ``int64 [M]`` each robot's compact cell, updated in place.
        heading: ``int64 [M]`` each robot's heading (0 east, 1 south, 2 west, 3 north),
            updated in place.
        target: ``int64 [M]`` the next cell each robot is committed to (``-1``: none),
            updated in place.
        order: ``int64 [M]`` robots by decreasing priority.
        goal_field: ``int64 [M]`` the row of ``fields`` of each robot's goal (``-1``).
        fields: ``int [F, C]`` BFS distance fields.
        nbr: ``int32 [C, 4]`` neighbours.
        tie: ``float64 [M, 5]`` tie-breaks in ``[0, 1)`` per candidate; the faced
            cell's is overwritten (it wins ties).
        occ_now: ``int64 [C]`` the robot in each cell (``-1``), kept current in place.
        occ_next: ``int64 [C]`` scratch, all ``-1`` on entry and exit.
        nxt: ``int64 [M]`` scratch.
        action: ``int64 [M]`` out: each robot's action this timestep.
    """
    m = pos.shape[0]
    nxt[:] = -1
    for i in range(m):
        ahead = _HEADING_OF[heading[i]]
        tie[i, ahead] = min(tie[i, ahead], _PREFER_AHEAD)  # a guide's mark stays
        if target[i] >= 0:
            nxt[i] = target[i]
            occ_next[target[i]] = i
    pibt_plan(pos, order, goal_field, fields, nbr, tie, occ_now, occ_next, nxt)
    for i in range(m):
        action[i] = _action(pos[i], nxt[i], heading[i], nbr)
        target[i] = -1 if nxt[i] == pos[i] else nxt[i]
    checked = np.zeros(m, np.bool_)
    chain = np.empty(m, np.int64)
    _cancel_blocked(pos, target, action, occ_now, checked, chain)
    for i in range(m):
        occ_next[nxt[i]] = -1
        if action[i] == FORWARD:
            occ_now[pos[i]] = -1
    for i in range(m):
        a = action[i]
        if a == FORWARD:
            pos[i] = target[i]
            occ_now[pos[i]] = i
            target[i] = -1
        elif a == TURN_CW:
            heading[i] = (heading[i] + 1) % 4
        elif a == TURN_CCW:
            heading[i] = (heading[i] + 3) % 4
