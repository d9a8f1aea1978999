"""Observation layouts of the PettingZoo env: spaces, every agent's view, the global state.

Two choices make a layout (:class:`ObservationLayout`):

* ``observation``: ``"full"`` (the robot table ``robots [M, 3]`` plus the robot's own view
  of the queue) or ``"compact"`` (the own view only: its size does not grow with ``M``;
  the ``rivals`` block is the fixed-size summary of the other robots);
* ``obs_format``: ``"dict"`` (one array per feature) or ``"flat"`` (the same features in
  one float32 vector, for Box-only wrappers such as SuperSuit's ``flatten_v0``).

:class:`AgentViews` computes the features of a decision once, for any number of
``observe`` calls. :func:`state_vector` is the global state (``AECEnv.state``).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from math import prod
from typing import Any

import numpy as np
from gymnasium import spaces

from rtaw_marl.envs.features import (
    NUM_RIVALS,
    RELATION_FEATURES,
    RIVAL_FEATURES,
    ROBOT_FEATURES,
    TASK_FEATURES,
    all_relational_features,
    relational_features,
    robot_features,
    task_features,
)
from rtaw_marl.errors import ConfigError
from rtaw_marl.sim.core import WarehouseSim

__all__ = [
    "FEATURE_KEYS",
    "OBSERVATIONS",
    "OBS_FORMATS",
    "QUEUE_STATE_FEATURES",
    "AgentViews",
    "Features",
    "ObservationLayout",
    "state_vector",
]

#: The ``observation`` options.
OBSERVATIONS = ("full", "compact")
#: The ``obs_format`` options.
OBS_FORMATS = ("dict", "flat")
#: Feature keys of each ``observation`` option, in the order of the flat vector.
FEATURE_KEYS: dict[str, tuple[str, ...]] = {
    "full": ("robots", "tasks", "agent", "relations", "rivals"),
    "compact": ("tasks", "agent", "relations", "rivals"),
}
#: Columns of the queue rows of the global state, after the robot table.
QUEUE_STATE_FEATURES = ("ox", "oy", "dx", "dy", "length", "wait", "queued")

Features = dict[str, np.ndarray] | np.ndarray


@dataclass(frozen=True)
class ObservationLayout:
    """Shapes and spaces of one observation option.

    Args:
        observation: ``"full"`` or ``"compact"``.
        obs_format: ``"dict"`` or ``"flat"``.
        num_robots: ``M``.
        queue_len: ``N``.

    Raises:
        ConfigError: ``observation`` or ``obs_format`` is not one of the options.
    """

    observation: str
    obs_format: str
    num_robots: int
    queue_len: int

    def __post_init__(self) -> None:
        for name, value, options in (
            ("observation", self.observation, OBSERVATIONS),
            ("obs_format", self.obs_format, OBS_FORMATS),
        ):
            if value not in options:
                raise ConfigError(f"Unknown {name} {value!r}. Available: {', '.join(options)}")

    @property
    def keys(self) -> tuple[str, ...]:
        """The feature keys, in the order of the flat vector."""
        return FEATURE_KEYS[self.observation]

    @property
    def shapes(self) -> dict[str, tuple[int, ...]]:
        """Shape of each feature of one agent's observation."""
        m, n = self.num_robots, self.queue_len
        every = {
            "robots": (m, len(ROBOT_FEATURES)),
            "tasks": (n, len(TASK_FEATURES)),
            "agent": (len(ROBOT_FEATURES),),
            "relations": (n, len(RELATION_FEATURES)),
            "rivals": (n, NUM_RIVALS, len(RIVAL_FEATURES)),
        }
        return {key: every[key] for key in self.keys}

    @property
    def flat_slices(self) -> dict[str, slice]:
        """Where each feature lies in the flat vector (each flattened in C order)."""
        out, start = {}, 0
        for key, shape in self.shapes.items():
            out[key] = slice(start, start + prod(shape))
            start += prod(shape)
        return out

    @property
    def flat_size(self) -> int:
        """Length of the flat vector: ``3M + 46N + 3`` (full) or ``46N + 3`` (compact)."""
        return sum(prod(shape) for shape in self.shapes.values())

    def features_space(self) -> spaces.Dict | spaces.Box:
        """The space of the ``"observation"`` entry.

        Every Box is declared ``(-inf, inf)`` with scalar bounds, on purpose: TorchRL turns
        a finite bound into a ``Bounded`` spec, and ``PettingZooWrapper`` indexes the
        stacked spec once per agent per step, copying the bounds of all ``M`` agents each
        time (measured at ``M = 1000``: 6-15 ms per agent against 0.04-0.13 ms unbounded).
        The real ranges are in the env docstring.
        """
        if self.obs_format == "flat":
            return spaces.Box(-np.inf, np.inf, (self.flat_size,), np.float32)
        return spaces.Dict(
            {
                key: spaces.Box(-np.inf, np.inf, shape, np.float32)
                for key, shape in self.shapes.items()
            }
        )

    def space(self) -> spaces.Dict:
        """One agent's observation space: ``{"observation": ..., "action_mask": int8 [N]}``."""
        mask = spaces.Box(0, 1, (self.queue_len,), np.int8)
        return spaces.Dict({"observation": self.features_space(), "action_mask": mask})

    def state_space(self) -> spaces.Box:
        """The space of :func:`state_vector`: ``float32 [3M + 7N]``, every entry ``>= 0``."""
        size = self.num_robots * len(ROBOT_FEATURES) + self.queue_len * len(QUEUE_STATE_FEATURES)
        return spaces.Box(0.0, np.inf, (size,), np.float32)

    def flatten(self, features: Mapping[str, np.ndarray]) -> np.ndarray:
        """Dict features ``[..., *shape]`` (leading dims shared) -> ``float32 [..., flat_size]``."""
        shapes = self.shapes
        lead = features["agent"].shape[:-1]
        parts = [np.reshape(features[key], (*lead, prod(shapes[key]))) for key in self.keys]
        return np.concatenate(parts, axis=-1, dtype=np.float32)

    def unflatten(self, flat: np.ndarray) -> dict[str, np.ndarray]:
        """Flat features ``[..., flat_size]`` -> dict features (views where possible)."""
        lead = flat.shape[:-1]
        slices = self.flat_slices
        return {
            key: flat[..., slices[key]].reshape(*lead, *shape) for key, shape in self.shapes.items()
        }


def state_vector(sim: WarehouseSim) -> np.ndarray:
    """The global state: the robot table, then the queue.

    Returns:
        ``float32 [3M + 7N]``: ``robots [M, 3]`` (``(x, y, time_until_free) / L``, as
        the ``robots`` feature) then ``[N, 7]`` queue rows ``(ox, oy, dx, dy, length,
        wait) / L`` and ``queued`` (1 or 0), flattened in C order; empty slots are zeros.
    """
    scale = sim.layout.scale
    robots = robot_features(sim.robot_xy, sim.robot_free_at, sim.time, scale)
    queue = np.empty((sim.queue_len, len(QUEUE_STATE_FEATURES)), dtype=np.float32)
    queue[:, :4] = sim.queue_rows / scale
    queue[:, 4] = sim.queue_length / scale
    queue[:, 5] = sim.queue_waits() / scale
    queue[:, 6] = sim.queue_mask
    return np.concatenate([robots.ravel(), queue.ravel()])


class AgentViews:
    """Every agent's observation of the current decision, each computed at most once.

    The acting robot's view is computed alone, with the very functions of the batched
    TorchRL env (bit-identical observations): a policy reading ``last()`` pays for one
    view. The other robots' views are computed together, in ``O(M N)``, on the first
    request for one of them in a decision (TorchRL's ``PettingZooWrapper`` observes
    every robot every step).

    Returned arrays are shared between calls (and ``robots`` between agents) until the
    next decision; a caller that modifies one must copy it first.

    Args:
        sim: The env's simulator.
        layout: The observation layout.
    """

    def __init__(self, sim: WarehouseSim, layout: ObservationLayout) -> None:
        self.sim = sim
        self.layout = layout
        self.scale = sim.layout.scale
        self.clear()

    def clear(self) -> None:
        """Forget the cached decision (call after a reset)."""
        self._stamp = -1
        self._acting: Features | None = None
        self._others: Features | None = None
        self._all: Features | None = None

    def observe(self, robot: int) -> dict[str, Any]:
        """``{"observation": features, "action_mask": int8 [N]}`` of ``robot``.

        The mask is the queue's occupancy for the acting robot of a live decision and all
        zeros otherwise.
        """
        sim = self.sim
        self._refresh()
        if robot == sim.robot and not sim.done:
            if self._acting is None:
                self._acting = self._acting_view()
            return {"observation": self._acting, "action_mask": self._mask}
        if self._others is None:
            self._others = self._other_views()
        return {"observation": self._pick(robot), "action_mask": self._zero_mask}

    def observe_all(self) -> tuple[Features, np.ndarray]:
        """Every robot's observation at once, in robot order.

        Returns:
            ``(features, masks)``: the features stacked over robots (``[M, ...]`` per key,
            or ``[M, flat_size]``), each row equal to :meth:`observe`'s for that robot
            (the acting row bit-identical), and the masks ``int8 [M, N]``. The arrays are
            shared until the next decision (``robots`` may be a read-only broadcast view).
        """
        sim = self.sim
        self._refresh()
        if self._others is None:
            self._others = self._other_views()
        masks = np.zeros((sim.num_robots, sim.queue_len), dtype=np.int8)
        if sim.done:
            return self._others, masks
        if self._acting is None:
            self._acting = self._acting_view()
        masks[sim.robot] = self._mask
        if self._all is None:
            self._all = _with_row(self._others, sim.robot, self._acting)
        return self._all, masks

    def _refresh(self) -> None:
        """Per-decision inputs shared by every view."""
        sim = self.sim
        if self._stamp == sim.decisions:
            return
        self._robot_rows = robot_features(sim.robot_xy, sim.robot_free_at, sim.time, self.scale)
        self._mask = sim.queue_mask.astype(np.int8)
        self._zero_mask = np.zeros(sim.queue_len, dtype=np.int8)
        self._all_dist = sim.distance_matrix()
        self._remaining = sim.robot_remaining()
        self._waits = sim.queue_waits()
        self._chain = sim.chain_distances()
        self._acting = self._others = self._all = None
        self._stamp = sim.decisions

    def _acting_view(self) -> Features:
        sim = self.sim
        features = {"robots": self._robot_rows}
        features["tasks"] = task_features(
            sim.queue_rows, sim.queue_length, sim.robot_distances(), sim.queue_mask, self.scale
        )
        features["agent"] = self._robot_rows[sim.robot].copy()
        features["relations"], features["rivals"] = relational_features(
            self._all_dist, self._remaining, sim.robot, sim.queue_length, self._waits,
            self._chain, sim.queue_mask, self.scale,
        )  # fmt: skip
        return self._format(features)

    def _other_views(self) -> Features:
        """Every robot's view at once: ``[M, ...]`` per feature (or ``[M, flat_size]``)."""
        sim = self.sim
        m, n = sim.num_robots, sim.queue_len
        rows = self._robot_rows
        features = {"robots": np.broadcast_to(rows, (m, *rows.shape))}
        features["tasks"] = task_features(
            np.broadcast_to(sim.queue_rows, (m, n, 4)),
            np.broadcast_to(sim.queue_length, (m, n)),
            self._all_dist,
            np.broadcast_to(sim.queue_mask, (m, n)),
            self.scale,
        )
        features["agent"] = rows
        features["relations"], features["rivals"] = all_relational_features(
            self._all_dist, self._remaining, sim.queue_length, self._waits, self._chain,
            sim.queue_mask, self.scale,
        )  # fmt: skip
        return self._format(features)

    def _format(self, features: dict[str, np.ndarray]) -> Features:
        if self.layout.obs_format == "flat":
            return self.layout.flatten(features)
        return {key: features[key] for key in self.layout.keys}

    def _pick(self, robot: int) -> Features:
        others = self._others
        if isinstance(others, np.ndarray):
            return others[robot]
        # robots is the same table for every agent: hand out the [M, 3] array itself.
        return {key: self._robot_rows if key == "robots" else others[key][robot] for key in others}


def _with_row(stacked: Features, row: int, features: Features) -> Features:
    """A copy of ``stacked`` whose ``row`` is ``features`` (``robots``, the same table for
    every robot, is passed through as it is)."""
    if isinstance(stacked, np.ndarray):
        out = stacked.copy()
        out[row] = features
        return out
    assert isinstance(features, dict)
    copies = {key: value.copy() for key, value in stacked.items() if key != "robots"}
    for key, value in copies.items():
        value[row] = features[key]
    return {key: copies.get(key, value) for key, value in stacked.items()}
