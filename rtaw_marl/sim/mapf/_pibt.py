"""Compiled kernels of lifelong PIBT: the compact graph, its BFS fields and one timestep.

PIBT (priority inheritance with backtracking; Okumura et al., AIJ 2022) plans one
timestep for every robot at once: in priority order, each robot takes the free
neighbouring cell (or its own) nearest its goal; a robot in the way *inherits* the
asker's priority and must move first, and when it cannot, the asker tries its next cell.
No two robots end in one cell, and no two swap (a robot never enters the cell its
parent in the inheritance chain is leaving).

The graph is the layout's free cells, numbered ``0..C-1`` (compact: a field is
``C`` entries, not ``W x H``); ``nbr [C, 4]`` holds the 4-connected neighbours
(``-1``: none).
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["bfs_compact", "compact_graph", "pibt_plan", "pibt_step"]


def compact_graph(obstacles: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The free cells of ``obstacles bool [H, W]`` as a compact graph.

    Returns:
        ``index int32 [H, W]`` (the compact id of each cell, ``-1`` if blocked),
        ``cells int64 [C, 2]`` (``(x, y)`` of each id) and ``nbr int32 [C, 4]``.
    """
    h, w = obstacles.shape
    ys, xs = np.nonzero(~obstacles)
    index = np.full((h + 2, w + 2), -1, dtype=np.int32)
    index[ys + 1, xs + 1] = np.arange(len(xs), dtype=np.int32)
    nbr = np.stack(
        [index[ys + 1, xs + 2], index[ys + 1, xs], index[ys + 2, xs + 1], index[ys, xs + 1]],
        axis=1,
    )
    return index[1:-1, 1:-1].copy(), np.stack([xs, ys], axis=1).astype(np.int64), nbr


@njit(cache=True, nogil=True)
def bfs_compact(nbr: np.ndarray, source: int, out: np.ndarray) -> None:
    """``out [C]``: BFS distances from compact cell ``source`` (``-1``: unreachable)."""
    out[:] = -1
    queue = np.empty(nbr.shape[0], np.int32)
    out[source] = 0
    queue[0] = source
    head, tail = 0, 1
    while head < tail:
        cell = queue[head]
        head += 1
        step = out[cell] + 1
        for k in range(4):
            nxt = nbr[cell, k]
            if nxt >= 0 and out[nxt] < 0:
                out[nxt] = step
                queue[tail] = nxt
                tail += 1


@njit(cache=True, nogil=True)
def _candidates(i, pos, goal_field, fields, nbr, tie, cand, keys) -> int:
    """Fill ``cand`` with robot ``i``'s cell and free neighbours, nearest its goal first
    (a robot without a goal prefers to stay); returns how many. ``keys [5]`` is scratch."""
    cur = pos[i]
    count = 0
    for k in range(5):
        c = cur if k == 4 else nbr[cur, k]
        if c < 0:
            continue
        if goal_field[i] >= 0:
            d = fields[goal_field[i], c]
            key = 1e9 if d < 0 else float(d)
        else:
            key = 0.0 if c == cur else 1.0
        key += 0.5 * tie[i, k]  # tie[i, k] in [0, 1): breaks equal distances only
        j = count
        while j > 0 and keys[j - 1] > key:
            keys[j] = keys[j - 1]
            cand[j] = cand[j - 1]
            j -= 1
        keys[j] = key
        cand[j] = c
        count += 1
    return count


@njit(cache=True, nogil=True)
def _pibt(
    root, pos, nxt, occ_now, occ_next, goal_field, fields, nbr, tie, frames, cands, keys
) -> None:
    """PIBT from robot ``root``, with an explicit stack (numba cannot cache recursive
    functions): frame ``d`` holds a robot, its parent, its candidates and the next to try.

    ``frames int64 [M, 4]`` (robot, parent, next candidate, count) and ``cands int64
    [M, 5]`` are scratch."""
    depth = 0
    frames[0, 0], frames[0, 1], frames[0, 2] = root, -1, 0
    frames[0, 3] = _candidates(root, pos, goal_field, fields, nbr, tie, cands[0], keys)
    while depth >= 0:
        i, parent = frames[depth, 0], frames[depth, 1]
        pushed = False
        while frames[depth, 2] < frames[depth, 3]:
            v = cands[depth, frames[depth, 2]]
            frames[depth, 2] += 1
            if occ_next[v] >= 0:
                continue
            if parent >= 0 and v == pos[parent]:
                continue  # the parent is moving into our cell: entering its cell is a swap
            j = occ_now[v]
            if j >= 0 and j != i and nxt[j] == pos[i]:
                continue  # j already moves into our cell
            occ_next[v] = i
            nxt[i] = v
            if j >= 0 and j != i and nxt[j] < 0:
                # j must move first (priority inheritance); on failure it stays in v
                # (its fallback takes v) and we try our next cell.
                depth += 1
                frames[depth, 0], frames[depth, 1], frames[depth, 2] = j, i, 0
                frames[depth, 3] = _candidates(
                    j, pos, goal_field, fields, nbr, tie, cands[depth], keys
                )
                pushed = True
                break
            # Success: this robot and every ancestor waiting on it are planned.
            depth = -1
            pushed = True
            break
        if pushed:
            continue
        # No cell left: stay (overriding any reservation of our cell), report failure.
        nxt[i] = pos[i]
        occ_next[pos[i]] = i
        depth -= 1


@njit(cache=True, nogil=True)
def pibt_plan(
    pos: np.ndarray,
    order: np.ndarray,
    goal_field: np.ndarray,
    fields: np.ndarray,
    nbr: np.ndarray,
    tie: np.ndarray,
    occ_now: np.ndarray,
    occ_next: np.ndarray,
    nxt: np.ndarray,
) -> None:
    """Plan one timestep: ``nxt`` gets the next cell of every robot whose ``nxt`` is
    ``-1`` on entry (the others are already planned, their cells marked in
    ``occ_next``; they are never pushed). Arguments as :func:`pibt_step`."""
    frames = np.empty((pos.shape[0] + 1, 4), np.int64)
    cands = np.empty((pos.shape[0] + 1, 5), np.int64)
    keys = np.empty(5)
    for i in order:
        if nxt[i] < 0:
            _pibt(i, pos, nxt, occ_now, occ_next, goal_field, fields, nbr, tie, frames, cands, keys)


@njit(cache=True, nogil=True)
def pibt_step(
    pos: np.ndarray,
    order: np.ndarray,
    goal_field: np.ndarray,
    fields: np.ndarray,
    nbr: np.ndarray,
    tie: np.ndarray,
    occ_now: np.ndarray,
    occ_next: np.ndarray,
    nxt: np.ndarray,
) -> None:
    """Plan and apply one timestep: ``pos`` becomes every robot's next cell.

    Args:
        pos: ``int64 [M]`` each robot's compact cell, updated in place.
        order: ``int64 [M]`` robots by decreasing priority.
        goal_field: ``int64 [M]`` the row of ``fields`` of each robot's goal, ``-1``
            for none.
        fields: ``int [F, C]`` BFS distance fields.
        nbr: ``int32 [C, 4]`` neighbours.
        tie: ``float64 [M, 5]`` tie-breaks in ``[0, 1)`` per candidate (4 moves, stay).
        occ_now: ``int64 [C]`` the robot in each cell (``-1``), kept current in place.
        occ_next: ``int64 [C]`` scratch, all ``-1`` on entry and exit.
        nxt: ``int64 [M]`` scratch.
    """
    nxt[:] = -1
    pibt_plan(pos, order, goal_field, fields, nbr, tie, occ_now, occ_next, nxt)
    for i in range(pos.shape[0]):
        occ_now[pos[i]] = -1
    for i in range(pos.shape[0]):
        pos[i] = nxt[i]
        occ_now[nxt[i]] = i
        occ_next[nxt[i]] = -1
