"""Observation layouts of the PettingZoo env: every agent's view, the global state.

Two choices make a layout (:class:`ObservationLayout`):

* ``observation``: ``"full"`` (the robot table ``robots [M, 3]`` plus the robot's own view
  of the queue) or ``"compact"`` (the own view only: its size does not grow with ``M``;
  the ``rivals`` block is the fixed-size summary of the other robots);
* ``obs_format``: ``"dict"`` (one array per feature) or ``"flat"`` (the same features in
  one float32 vector, for Box-only wrappers such as SuperSuit's ``flatten_v0``).

:class:`AgentViews` computes the features of a decision once, for any number of
``observe`` calls. :func:`state_vector` is the global state (``AECEnv.state``).
:func:`read_features` reads a policy's features back from an observation. The
Gymnasium spaces of a layout are the env adapters' (:mod:`rtaw_marl.envs.spaces`):
this module imports neither Gymnasium nor PettingZoo.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from math import prod
from typing import Any

import numpy as np

from rtaw_marl.decision.features import (
    FEATURES,
    ROBOT_FEATURES,
    Decision,
    decision_features,
    feature_shapes,
    robot_features,
    sim_observation,
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
    "read_features",
    "state_vector",
]

#: The ``observation`` options.
OBSERVATIONS = ("full", "compact")
#: The ``obs_format`` options.
OBS_FORMATS = ("dict", "flat")
#: Feature keys of each ``observation`` option, in the order of the flat vector.
FEATURE_KEYS: dict[str, tuple[str, ...]] = {
    "full": FEATURES,
    "compact": tuple(key for key in FEATURES if key != "robots"),
}
#: Columns of the queue rows of the global state, after the robot table.
QUEUE_STATE_FEATURES = ("ox", "oy", "dx", "dy", "length", "wait", "queued")

Features = dict[str, np.ndarray] | np.ndarray


@dataclass(frozen=True)
class ObservationLayout:
    """Shapes and flat vector of one observation option.

    Its Gymnasium spaces are built by the env adapters (:mod:`rtaw_marl.envs.spaces`).

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
        every = feature_shapes(self.num_robots, self.queue_len)
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


def read_features(
    observation: Mapping[str, Any], keys: Iterable[str], reader: str = "this policy"
) -> dict[str, np.ndarray]:
    """The feature arrays ``keys`` of one ``warehouse_v1`` observation.

    Args:
        observation: ``{"observation": features, "action_mask": [N]}`` as ``observe`` or
            ``last()`` give it, with dict or flat features (``observation="full"`` or
            ``"compact"``; a flat vector's layout is told by its size and ``N``), or
            several agents' stacked (``[B, ...]``, as ``observe_all()`` gives them).
        keys: Feature keys to read (:data:`~rtaw_marl.decision.features.FEATURES`).
        reader: Who reads them, for the error message.

    Returns:
        ``{key: float32 array of one agent's shape}`` (``[B, ...]`` for stacked
        observations; views, not copies).

    Raises:
        ConfigError: The features lack one of ``keys`` (``compact`` has no ``robots``),
            or a flat vector has no ``warehouse_v1`` size.
    """
    features = observation["observation"]
    if not isinstance(features, Mapping):
        features = _unflatten(np.asarray(features), np.shape(observation["action_mask"])[-1])
    missing = [key for key in keys if key not in features]
    if missing:
        raise ConfigError(
            f"{reader} reads {', '.join(missing)} from the observation, which has only "
            f"{', '.join(features)}: build the env with observation='full'"
        )
    return {key: np.asarray(features[key]) for key in keys}


def _unflatten(flat: np.ndarray, queue_len: int) -> dict[str, np.ndarray]:
    """A flat vector -> dict features; ``3M + 46N + 3`` values (full) or ``46N + 3``."""
    robots = flat.shape[-1] - ObservationLayout("compact", "flat", 0, queue_len).flat_size
    if robots < 0 or robots % len(ROBOT_FEATURES):
        raise ConfigError(
            f"a flat observation of {flat.shape[-1]} values with N={queue_len} is not a "
            f"warehouse_v1 layout (3M + 46N + 3 or 46N + 3 values)"
        )
    kind = "full" if robots else "compact"
    return ObservationLayout(kind, "flat", robots // 3, queue_len).unflatten(flat)


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

        The mask is the queue's occupancy (the unassigned tasks) for the acting robot of
        a live decision and all zeros otherwise. With ``sim.reassign`` the observation
        also holds ``"reassignable": int8 [N]``, the slots of tasks held by a robot on its
        way to the pickup that the acting robot may also take (zeros for the other
        agents): legal actions beyond the mask, so a policy that knows nothing of
        reassignment acts as before.
        """
        sim = self.sim
        self._refresh()
        if robot == sim.robot and not sim.done:
            if self._acting is None:
                self._acting = self._acting_view()
            out = {"observation": self._acting, "action_mask": self._mask}
            held = self._held
        else:
            if self._others is None:
                self._others = self._other_views()
            out = {"observation": self._pick(robot), "action_mask": self._zero_mask}
            held = self._zero_mask
        if sim.config.reassign:
            out["reassignable"] = held
        return out

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
        self._mask = sim.queue_mask.astype(np.int8)
        self._held = sim.reassignable().astype(np.int8)
        self._zero_mask = np.zeros(sim.queue_len, dtype=np.int8)
        self._acting = self._others = self._all = None
        self._stamp = sim.decisions

    def _acting_view(self) -> Features:
        return self._format(sim_observation(self.sim, self.layout.keys))

    def _other_views(self) -> Features:
        """Every robot's view at once: ``[M, ...]`` per feature (or ``[M, flat_size]``)."""
        viewers = np.arange(self.sim.num_robots)
        decision = Decision.of_sim(self.sim, _ALL_FEATURES)
        features = decision_features(decision, (*self.layout.keys, "agent"), viewers)
        self._robot_rows = features["agent"]  # [M, 3]: every robot's row, writable
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


#: Every feature, as ``Decision.of_sim`` takes it at every decision.
_ALL_FEATURES = frozenset(FEATURES)


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
