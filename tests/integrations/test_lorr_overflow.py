"""The robots LoRR's clock leaves unserved, with ``overflow=nearest``: each takes the
nearest open pickup by grid distance, the robots nearest a pickup choosing first, and
those whose nearest went to others choose again among the rest."""

from __future__ import annotations

import numpy as np
import pytest

from rtaw_marl.integrations.lorr.overflow import nearest_pairs

pytestmark = pytest.mark.unit


def _reference(robot_xy: np.ndarray, task_xy: np.ndarray, k: int) -> np.ndarray:
    """The same greedy written plainly: distances of each robot's choice (inf: none)."""
    dist = np.abs(robot_xy[:, None, :] - task_xy[None, :, :]).sum(axis=2).astype(float)
    taken = np.zeros(len(task_xy), dtype=bool)
    out = np.full(len(robot_xy), np.inf)
    left = list(range(len(robot_xy)))
    while left and not taken.all():
        d = np.where(taken, np.inf, dist)  # a round sees the tasks left
        kth = np.sort(d, axis=1)[:, min(k, int((~taken).sum())) - 1]
        later = []
        for row in sorted(left, key=lambda r: (d[r].min(), r)):
            # Its k nearest of the round (up to ties at the k-th), the nearest not taken.
            free = ~taken & (d[row] <= kth[row])
            if free.any():
                choice = np.flatnonzero(free)[np.argmin(d[row][free])]
                taken[choice] = True
                out[row] = dist[row, choice]
            else:
                later.append(row)
        left = later
    return out


@pytest.mark.parametrize("seed", range(5))
def test_each_robot_takes_its_nearest_pickup_left_in_order(seed: int) -> None:
    rng = np.random.default_rng(seed)
    # Distinct distances (no ties for the k-d tree to break its own way).
    robot_xy = rng.choice(10_000, size=(40, 2), replace=False) * 7
    task_xy = rng.choice(10_000, size=(25, 2), replace=False) * 7 + 3
    got = nearest_pairs(robot_xy, task_xy, k=4)
    assert len(set(got[got >= 0].tolist())) == int((got >= 0).sum())  # a task at most once
    dist = np.abs(robot_xy - task_xy[np.maximum(got, 0)]).sum(axis=1).astype(float)
    want = _reference(robot_xy, task_xy, 4)
    np.testing.assert_array_equal(np.where(got >= 0, dist, np.inf), want)


def test_robots_whose_nearest_went_to_others_choose_again_among_the_rest() -> None:
    """Ten robots in a row want the same two nearest pickups (k = 2): the two nearest
    take them, the others choose again among the tasks left, until every robot has one."""
    robot_xy = np.stack([np.arange(10), np.zeros(10, dtype=int)], axis=1)
    task_xy = np.array([[0, 1], [1, 1], *[[50 + i, 0] for i in range(12)]])
    got = nearest_pairs(robot_xy, task_xy, k=2)
    assert (got >= 0).all()
    assert len(set(got.tolist())) == 10
    assert set(got[:2].tolist()) == {0, 1}
    # Fewer tasks than robots: the robots farthest from every pickup are left.
    few = nearest_pairs(robot_xy, task_xy[:4], k=2)
    assert sorted(few[few >= 0].tolist()) == [0, 1, 2, 3]
    assert (few[:2] >= 0).all()
    assert int((few < 0).sum()) == 6


def test_more_tasks_than_robots_serves_every_robot_and_empty_inputs() -> None:
    robot_xy = np.array([[0, 0], [9, 9]])
    task_xy = np.array([[8, 9], [1, 0], [5, 5]])
    np.testing.assert_array_equal(nearest_pairs(robot_xy, task_xy), [1, 0])
    assert nearest_pairs(robot_xy, task_xy[:0]).tolist() == [-1, -1]
    assert nearest_pairs(robot_xy[:0], task_xy).tolist() == []
