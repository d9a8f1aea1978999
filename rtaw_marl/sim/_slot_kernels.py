"""Compiled kernels of the queue slots' distance queries (:mod:`rtaw_marl.sim.distances`).

A decision queries small matrices (``M x N``, one row, one column): NumPy's broadcasting
and temporaries cost more than the arithmetic there. These loops compute the same
values: ``math.hypot`` equals ``np.hypot`` bit for bit on every integer difference a
grid has (checked over ``[-1100, 1100]^2`` in the tests), and a field lookup is exact.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["euclidean_from", "euclidean_refresh", "field_gather", "field_refresh"]


@njit(cache=True, nogil=True)
def euclidean_from(xy: np.ndarray, targets: np.ndarray, out: np.ndarray) -> None:
    """``out[p, k]``: the straight-line distance from cell ``xy[p]`` to ``targets[k]``.

    Args:
        xy: ``int64 [P, 2]`` (or float64) source cells.
        targets: ``float64 [K, 2]`` target cells.
        out: ``float64 [P, K]``, overwritten.
    """
    for p in range(xy.shape[0]):
        x, y = float(xy[p, 0]), float(xy[p, 1])
        for k in range(targets.shape[0]):
            out[p, k] = math.hypot(x - targets[k, 0], y - targets[k, 1])


@njit(cache=True, nogil=True)
def field_gather(
    fields: np.ndarray, rows: np.ndarray, xy: np.ndarray, row_stride: int, out: np.ndarray
) -> None:
    """``out[p, k]``: field ``rows[k]`` at cell ``xy[p]`` (a grid padded by one cell).

    Args:
        fields: ``int32 [N, cells]`` distance fields of the padded grid.
        rows: ``int64 [K]`` which fields.
        xy: ``int64 [P, 2]`` source cells.
        row_stride: ``W + 2``.
        out: ``float64 [P, K]``, overwritten.
    """
    for p in range(xy.shape[0]):
        cell = (xy[p, 1] + 1) * row_stride + xy[p, 0] + 1
        for k in range(rows.shape[0]):
            out[p, k] = fields[rows[k], cell]


@njit(cache=True, nogil=True)
def euclidean_refresh(
    xy: np.ndarray, targets: np.ndarray, rows: np.ndarray, cols: np.ndarray, out: np.ndarray
) -> None:
    """Recompute rows ``rows`` and columns ``cols`` of ``out`` (:func:`euclidean_from`'s
    ``[P, K]`` matrix of ``xy [P, 2]`` and ``targets [K, 2]``) in place."""
    for r in rows:
        x, y = float(xy[r, 0]), float(xy[r, 1])
        for k in range(targets.shape[0]):
            out[r, k] = math.hypot(x - targets[k, 0], y - targets[k, 1])
    for p in range(xy.shape[0]):
        x, y = float(xy[p, 0]), float(xy[p, 1])
        for c in cols:
            out[p, c] = math.hypot(x - targets[c, 0], y - targets[c, 1])


@njit(cache=True, nogil=True)
def field_refresh(
    fields: np.ndarray,
    xy: np.ndarray,
    row_stride: int,
    rows: np.ndarray,
    cols: np.ndarray,
    out: np.ndarray,
) -> None:
    """Recompute rows ``rows`` and columns ``cols`` of ``out`` (:func:`field_gather`'s
    ``[P, N]`` matrix of every field at the cells ``xy [P, 2]``) in place."""
    for r in rows:
        cell = (xy[r, 1] + 1) * row_stride + xy[r, 0] + 1
        for k in range(fields.shape[0]):
            out[r, k] = fields[k, cell]
    for p in range(xy.shape[0]):
        cell = (xy[p, 1] + 1) * row_stride + xy[p, 0] + 1
        for c in cols:
            out[p, c] = fields[c, cell]
