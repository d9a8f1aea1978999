"""Compiled kernels of traffic-flow guidance for lifelong PIBT (``navigator.guidance``).

PIBT alone sends every robot down a shortest path: in a crowded warehouse the robots of
opposite streams meet head-on in the aisles and block each other (gridlock at LoRR's
10,000 robots). LoRR's start kit guides its PIBT with congestion-aware *guide paths*
(Chen et al., "Traffic Flow Optimisation for Lifelong Multi-Agent Path Finding", AAAI
2024): each robot's path to its goal is planned on costs that grow with the other
robots' paths using the same aisle the other way (contraflow), and PIBT prefers the next
cell of the robot's guide path. This module keeps, for the whole fleet:

* ``flow int32 [C, 4]``: how many guide paths still to be walked use each directed edge
  ``c -> nbr[c, k]``;
* every robot's guide path in one buffer (``buf``, from ``start[r]``, ``length[r]``
  cells, the robot at index ``at[r]``).

A guide path is an A* search on edge costs ``1 + weight * contraflow`` with the goal's BFS
distance as heuristic (admissible: every edge costs at least 1). As a robot walks its
path the edges behind it leave the flow; a robot pushed off its path, or given a new
goal, gets a new one. PIBT then ranks a robot's neighbouring cells by BFS distance to the
goal as before, with the guide path's next cell first (:data:`GUIDE_TIE`: it gains 2.5,
more than the BFS distances of two neighbours of one cell can differ) and staying
second (:data:`STAY_TIE`: a robot waits for its guide cell rather than step off the
path into a cell one nearer its goal, as the kit's PIBT); it leaves the path only when
pushed.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = [
    "GUIDE_TIE",
    "guide_advance",
    "guide_compact",
    "guide_drop",
    "guide_plan",
    "guide_ties",
]

#: The tie-break given to the guide path's next cell. PIBT's key is the BFS distance plus
#: half the tie-break, so the next guide cell gains 2.5 over any other: more than the
#: two steps by which the distances of a cell's neighbours can differ.
GUIDE_TIE = -5.0
#: The tie-break of staying for a robot on its guide path: it waits for its guide cell
#: rather than step off the path into a cell one nearer its goal (as the kit's PIBT,
#: whose heuristic is the distance to the guide path plus the path left).
STAY_TIE = -3.0
#: The reverse of each of ``nbr``'s columns (``+x, -x, +y, -y``).
_REVERSE = np.array([1, 0, 3, 2], dtype=np.int64)


@njit(cache=True, nogil=True)
def _edge(nbr: np.ndarray, u: int, v: int) -> int:
    """The column ``k`` with ``nbr[u, k] == v`` (``-1``: not neighbours)."""
    for k in range(4):
        if nbr[u, k] == v:
            return k
    return -1


@njit(cache=True, nogil=True)
def _drop_rest(r, buf, start, length, at, flow, nbr) -> None:
    """Take the edges robot ``r`` has still to walk out of the flow; forget its path."""
    s = start[r]
    if s < 0:
        return
    for j in range(at[r], length[r] - 1):
        u, v = buf[s + j], buf[s + j + 1]
        flow[u, _edge(nbr, u, v)] -= 1
    start[r] = -1
    length[r] = 0
    at[r] = 0


@njit(cache=True, nogil=True)
def guide_drop(robots, buf, start, length, at, flow, nbr) -> None:
    """Forget the guide paths of ``robots int64 [K]`` (their edges leave the flow)."""
    for i in range(robots.shape[0]):
        _drop_rest(robots[i], buf, start, length, at, flow, nbr)


@njit(cache=True, nogil=True)
def guide_advance(pos, goal, buf, start, length, at, flow, nbr, need) -> None:
    """After a timestep: move each robot along its guide path, or mark it for a new one.

    A robot that stepped onto its path's next cell advances (the edge leaves the flow);
    one still on its current cell waits; one anywhere else, at its goal, or with a goal
    and no path gets ``need[r] = True`` (its old path is dropped).

    Args:
        pos: ``int64 [M]`` compact cells.
        goal: ``int64 [M]`` compact goal cells (``-1``: none).
        buf, start, length, at: The paths (module docstring).
        flow: ``int32 [C, 4]`` edge flows, updated.
        nbr: ``int32 [C, 4]`` neighbours.
        need: ``bool [M]`` out.
    """
    for r in range(pos.shape[0]):
        need[r] = False
        s = start[r]
        if s >= 0 and buf[s + length[r] - 1] != goal[r]:
            _drop_rest(r, buf, start, length, at, flow, nbr)  # the goal changed
            s = -1
        if s < 0:
            need[r] = goal[r] >= 0 and pos[r] != goal[r]
            continue
        j = at[r]
        if j + 1 < length[r] and pos[r] == buf[s + j + 1]:
            u = buf[s + j]
            flow[u, _edge(nbr, u, pos[r])] -= 1
            at[r] = j + 1
        elif pos[r] != buf[s + j]:
            _drop_rest(r, buf, start, length, at, flow, nbr)
            need[r] = True
        if start[r] >= 0 and at[r] == length[r] - 1:
            _drop_rest(r, buf, start, length, at, flow, nbr)  # arrived


@njit(cache=True, nogil=True)
def _push(heap_key, heap_node, size, key, node) -> int:
    i = size
    heap_key[i], heap_node[i] = key, node
    while i > 0:
        p = (i - 1) // 2
        if heap_key[p] <= heap_key[i]:
            break
        heap_key[p], heap_key[i] = heap_key[i], heap_key[p]
        heap_node[p], heap_node[i] = heap_node[i], heap_node[p]
        i = p
    return size + 1


@njit(cache=True, nogil=True)
def _pop(heap_key, heap_node, size) -> int:
    """Remove the root (read it before); returns the new size."""
    size -= 1
    heap_key[0], heap_node[0] = heap_key[size], heap_node[size]
    i = 0
    while True:
        a, b, m = 2 * i + 1, 2 * i + 2, i
        if a < size and heap_key[a] < heap_key[m]:
            m = a
        if b < size and heap_key[b] < heap_key[m]:
            m = b
        if m == i:
            return size
        heap_key[m], heap_key[i] = heap_key[i], heap_key[m]
        heap_node[m], heap_node[i] = heap_node[i], heap_node[m]
        i = m


@njit(cache=True, nogil=True)
def guide_plan(
    robots, pos, goal, goal_field, fields, nbr, flow, weight, buf, cursor, start, length,
    at, cost, parent, stamp, epoch, heap_key, heap_node,
) -> tuple[int, int]:  # fmt: skip
    """A new guide path for each of ``robots``, written into ``buf`` from ``cursor``,
    as long as ``buf`` has room for a path of every cell.

    Args:
        robots: ``int64 [K]`` the robots to plan (each with a goal, off it).
        pos, goal, goal_field: Cells, goal cells and goal field rows (``int64 [M]``).
        fields: ``int [F, C]`` BFS fields (the A* heuristic).
        nbr: ``int32 [C, 4]`` neighbours.
        flow: ``int32 [C, 4]`` edge flows (each new path's edges are added).
        weight: Cost of one unit of contraflow on an edge (its base cost is 1).
        buf, start, length, at: The paths.
        cost, parent, stamp: ``float64 [C]``, ``int64 [C]``, ``int64 [C]`` scratch
            (``stamp`` marks the cells seen by search number ``epoch + i``).
        epoch: The first search number (larger than any in ``stamp``).
        heap_key, heap_node: ``float64 [4 C]``, ``int64 [4 C]`` scratch.

    Returns:
        The new ``cursor`` and how many of ``robots`` were planned (fewer than ``K``
        when ``buf`` ran out of room: compact it, then plan the rest).
    """
    for i in range(robots.shape[0]):
        if cursor + stamp.shape[0] > buf.shape[0]:
            return cursor, i
        r = robots[i]
        mark = epoch + i
        src, dst, row = pos[r], goal[r], goal_field[r]
        stamp[src] = mark
        cost[src] = 0.0
        parent[src] = -1
        size = _push(heap_key, heap_node, 0, float(fields[row, src]), src)
        while size > 0:
            u = heap_node[0]
            f = heap_key[0]
            size = _pop(heap_key, heap_node, size)
            if u == dst:
                break
            if f > cost[u] + fields[row, u] + 1e-9:
                continue  # a stale entry
            for k in range(4):
                v = nbr[u, k]
                if v < 0 or fields[row, v] < 0:
                    continue
                g = cost[u] + 1.0 + weight * flow[v, _REVERSE[k]]
                if stamp[v] != mark or g < cost[v] - 1e-9:
                    stamp[v] = mark
                    cost[v] = g
                    parent[v] = u
                    size = _push(heap_key, heap_node, size, g + fields[row, v], v)
        if stamp[dst] != mark:  # unreachable: no guide (PIBT's field decides alone)
            start[r], length[r], at[r] = -1, 0, 0
            continue
        # Walk back from the goal, then write the path forwards.
        n = 0
        v = dst
        while v != -1:
            heap_node[n] = v
            n += 1
            v = parent[v]
        for j in range(n):
            buf[cursor + j] = heap_node[n - 1 - j]
        for j in range(n - 1):
            u, v = buf[cursor + j], buf[cursor + j + 1]
            flow[u, _edge(nbr, u, v)] += 1
        start[r], length[r], at[r] = cursor, n, 0
        cursor += n
    return cursor, robots.shape[0]


@njit(cache=True, nogil=True)
def guide_ties(pos, buf, start, length, at, nbr, tie) -> None:
    """Give each robot's guide path's next cell the tie-break :data:`GUIDE_TIE`."""
    for r in range(pos.shape[0]):
        s = start[r]
        if s < 0 or at[r] + 1 >= length[r]:
            continue
        k = _edge(nbr, pos[r], buf[s + at[r] + 1])
        if k >= 0:
            tie[r, k] = GUIDE_TIE
            tie[r, 4] = STAY_TIE


@njit(cache=True, nogil=True)
def guide_compact(buf, start, length, at, out) -> int:
    """Copy every path's cells still to walk into ``out`` (from 0); returns its cursor."""
    cursor = 0
    for r in range(start.shape[0]):
        s = start[r]
        if s < 0:
            continue
        n = length[r] - at[r]
        for j in range(n):
            out[cursor + j] = buf[s + at[r] + j]
        start[r], length[r], at[r] = cursor, n, 0
        cursor += n
    return cursor
