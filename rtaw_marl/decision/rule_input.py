"""The one input of a rule's decision, built from the simulator or from an observation.

A hand-written rule (``mpdm``, ``rbts``, ``lookahead``, ...) decides from a
:class:`RuleInput`: the queue's mask, the acting robot's distances, the robot table as
the free robot's observation holds it, and the distance model to measure more. The rule's
``act_sim(sim)`` and ``act(observation)`` are two ways to build that value
(:meth:`RuleInput.of_sim`, :meth:`RuleInput.of_observation`), followed by the same
``decide``; so the rule is written once and both paths choose the same slot.

The two builders agree by construction where a difference would change a choice: cells
are exact integers on both; times until free are the observation's float32 column on
both, turned back into float64 seconds by :func:`free_times`; the acting robot is the
first row of the robot table equal to its own (:func:`acting_row`); distances are the
distance model's. Only ``own_distances`` is read from the observation's float32 ``tasks``
column on the observation path (the simulator's float64 on the fast path), as the
network policies read it.

A :class:`~rtaw_marl.decision.features.Decision` is the other way round: the
simulator's arrays an observation is *computed from*.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from rtaw_marl.decision.features import robot_features
from rtaw_marl.decision.observations import read_features
from rtaw_marl.errors import ConfigError

if TYPE_CHECKING:
    from rtaw_marl.sim.core import WarehouseSim
    from rtaw_marl.sim.distances import DistanceModel

__all__ = ["RULE_NEEDS", "RuleInput", "acting_row", "free_times"]

#: The fields of :class:`RuleInput` a rule may ask for (its ``needs``); ``mask`` and
#: ``scale`` are always there. The fast path always has a ``distance_model`` and a
#: ``noise_mean``; needing them makes the observation path insist on them (a rule not
#: bound to an env has neither). ``robot`` is the acting robot's row as the observation
#: path finds it (:func:`acting_row`) on both paths; ``own_row`` fills the same field with
#: any row equal to it (the robot itself on the fast path, no search): enough for a rule to
#: which equal rows are interchangeable (RBTS), not for a whole-fleet assignment.
RULE_NEEDS = frozenset(
    ("distance_model", "noise_mean", "own_distances", "distances", "robot", "own_row",
     "robot_xy", "free_in", "queue_rows", "queue_length")
)  # fmt: skip


def free_times(column: np.ndarray, scale: float) -> np.ndarray:
    """``float64 [M]`` times until free from the observed ``time_until_free / L`` column.

    The observation is float32: where a time to the millisecond is what the observation
    holds (it rounds to the same float32), that time is taken, so that robots freed at
    the same second still tie (and the lowest id goes first) as in the simulator; other
    times (with completion noise) keep the observation's own value.

    Args:
        column: ``float32 [M]`` the robot table's last column.
        scale: ``L``.
    """
    column = np.asarray(column, dtype=np.float32)
    times = column.astype(np.float64) * scale
    rounded = np.round(times, 3)
    return np.where((rounded / scale).astype(np.float32) == column, rounded, times)


def acting_row(robots: np.ndarray, agent: np.ndarray) -> int:
    """The acting robot's row of ``robots float32 [M, 3]``: the first equal to ``agent
    float32 [3]``. Robots with equal rows (one cell, one observed time until free) are
    interchangeable for the rules, and an observation cannot tell them apart."""
    return int(np.all(robots == agent, axis=1).argmax())


# Not frozen: a frozen dataclass sets each field through object.__setattr__, a cost paid
# at every decision; the arrays are read, never written, by convention.
@dataclass(slots=True)
class RuleInput:
    """What a rule decides from (module docstring).

    Only the fields a rule ``needs`` (:data:`RULE_NEEDS`) are filled; the others are
    ``None`` (the fast path fills ``distance_model`` and ``noise_mean`` always). The arrays
    are read, never written (on the fast path some are the simulator's own, valid until
    its next step).

    Attributes:
        mask: ``bool [N]`` which slots hold a task.
        scale: ``L``, the observation's length scale.
        distance_model: The distance model; ``None`` only for a rule not bound to an env, on
            the observation path.
        noise_mean: The completion noise's mean, for rules that model it.
        own_distances: ``float64 [N]`` the acting robot's distance to each origin (empty
            slots: meaningless).
        distances: ``float64 [M, N]`` every robot's distance (from the cell where it
            will next be free) to each origin (empty slots: meaningless).
        robot: The acting robot's row of the robot table (:func:`acting_row`); with the
            need ``own_row`` instead of ``robot``, any row equal to it.
        robot_xy: ``int64 [M, 2]`` the cell where each robot will next be free.
        free_in: ``float64 [M]`` time until each robot is free, 0 for robots idle now,
            as the observation holds it (:func:`free_times`).
        queue_rows: ``int64 [N, 4]`` ``(ox, oy, dx, dy)`` per slot, zeros when empty.
        queue_length: ``float64 [N]`` each task's origin -> destination length (empty
            slots: meaningless).
    """

    mask: np.ndarray
    scale: float
    distance_model: DistanceModel | None = None
    noise_mean: float | None = None
    own_distances: np.ndarray | None = None
    distances: np.ndarray | None = None
    robot: int | None = None
    robot_xy: np.ndarray | None = None
    free_in: np.ndarray | None = None
    queue_rows: np.ndarray | None = None
    queue_length: np.ndarray | None = None

    @classmethod
    def of_sim(
        cls, sim: WarehouseSim, needs: Iterable[str] = (), noise_mean: float | None = None
    ) -> RuleInput:
        """``sim``'s current decision, with the fields ``needs`` asks for (``act_sim``).

        Args:
            sim: The simulator, at a decision.
            needs: Fields to fill (:data:`RULE_NEEDS`).
            noise_mean: The completion noise's mean to model; ``None``: the simulator's.
        """
        needs = _checked(needs)
        scale = sim.layout.scale
        robot = None
        if "robot" in needs:
            robot = _acting_robot(sim)
        elif "own_row" in needs:
            robot = int(sim.robot)
        free_in = None
        if "free_in" in needs:
            # The times as the observation's float32 column holds them, so that they are
            # those act() reads.
            table = robot_features(sim.robot_xy, sim.robot_free_at, sim.time, scale)
            free_in = free_times(table[:, 2], scale)
        return cls(
            sim.queue_mask, scale, sim.distance_model,
            sim.config.noise_mean if noise_mean is None else noise_mean,
            own_distances=sim.robot_distances() if "own_distances" in needs else None,
            distances=sim.distance_matrix() if "distances" in needs else None,
            robot=robot, robot_xy=sim.robot_xy if "robot_xy" in needs else None,
            free_in=free_in, queue_rows=sim.queue_rows if "queue_rows" in needs else None,
            queue_length=sim.queue_length if "queue_length" in needs else None,
        )  # fmt: skip

    @classmethod
    def of_observation(
        cls,
        observation: Mapping[str, Any],
        needs: Iterable[str] = (),
        *,
        distance_model: DistanceModel | None = None,
        scale: float = 1.0,
        noise_mean: float | None = None,
        reader: str = "this rule",
    ) -> RuleInput:
        """The decision of a ``warehouse_v1`` observation, with the fields ``needs`` asks
        for (``act``).

        Args:
            observation: ``{"observation": features, "action_mask": [N]}`` of the free
                robot (dict or flat features; the robot table needs ``observation="full"``).
            needs: Fields to fill (:data:`RULE_NEEDS`).
            distance_model: The env's distance model (``distances`` and
                ``distance_model`` need it).
            scale: The env's ``L``.
            noise_mean: The env's completion noise mean (``noise_mean`` needs it).
            reader: The rule's name, for the error messages.

        Raises:
            ConfigError: A needed distance model or noise mean is missing (the rule was not
                built with ``make_baseline(name, env=env)``), or the observation lacks
                a needed feature (``compact`` has no robot table).
        """
        needs = _checked(needs)
        missing = [
            what
            for what, need, have in (
                ("distance model", {"distances", "distance_model"}, distance_model),
                ("noise mean", {"noise_mean"}, noise_mean),
            )
            if needs & need and have is None
        ]
        if missing:
            raise ConfigError(
                f"{reader} on observations needs the env's {' and '.join(missing)}: "
                f"make_baseline({reader!r}, env=env)"
            )
        mask = np.asarray(observation["action_mask"], dtype=bool)
        # The distances are measured from the observed cells to the observed origins.
        tasks_needed = bool(needs & {"own_distances", "queue_rows", "distances", "queue_length"})
        robots_needed = bool(needs & {"robot", "own_row", "robot_xy", "free_in", "distances"})
        agent_needed = bool(needs & {"robot", "own_row"})
        keys = [key for key, wanted in (("robots", robots_needed), ("tasks", tasks_needed),
                                        ("agent", agent_needed)) if wanted]  # fmt: skip
        features = read_features(observation, keys, reader) if keys else {}
        own = rows = robot = robot_xy = free_in = dist = length = None
        if tasks_needed:
            tasks = features["tasks"].astype(np.float64) * scale
            own = tasks[:, 4] if "own_distances" in needs else None
            length = tasks[:, 5] if "queue_length" in needs else None
            rows = np.rint(tasks[:, :4]).astype(np.int64)
        if robots_needed:
            table = features["robots"]
            robot_xy = np.rint(table[:, :2].astype(np.float64) * scale).astype(np.int64)
            if agent_needed:
                robot = acting_row(table, features["agent"])
            if "free_in" in needs:
                free_in = free_times(table[:, 2], scale)
        if "distances" in needs:
            assert distance_model is not None
            assert rows is not None
            assert robot_xy is not None
            # Only the queued origins are measured; the empty slots' columns stay 0.
            dist = np.zeros((len(robot_xy), len(mask)))
            dist[:, mask] = distance_model.distance_matrix(robot_xy, rows[mask, :2])
        return cls(
            mask, float(scale), distance_model, noise_mean, own_distances=own, distances=dist,
            robot=robot, robot_xy=robot_xy if "robot_xy" in needs else None,
            free_in=free_in, queue_rows=rows if "queue_rows" in needs else None,
            queue_length=length,
        )  # fmt: skip


def _acting_robot(sim: WarehouseSim) -> int:
    """:func:`acting_row` of ``sim``'s robot table, computed for the robots that share
    the acting robot's cell only: rows with different cells differ (``x / L`` and
    ``y / L`` in float32 are distinct for distinct cells), so the others cannot match."""
    me, xy = sim.robot, sim.robot_xy
    earlier = np.flatnonzero((xy[:me] == xy[me]).all(axis=1))
    if not earlier.size:
        return int(me)
    rows = np.append(earlier, me)
    table = robot_features(xy[rows], sim.robot_free_at[rows], sim.time, sim.layout.scale)
    return int(rows[acting_row(table, table[-1])])


def _checked(needs: Iterable[str]) -> frozenset[str]:
    # Rules pass the same frozenset at every decision: checked once, then looked up.
    if isinstance(needs, frozenset) and needs in _CHECKED:
        return needs
    needs = needs if isinstance(needs, frozenset) else frozenset(needs)
    if not needs <= RULE_NEEDS:
        raise ValueError(f"unknown needs {sorted(needs - RULE_NEEDS)}; known: {sorted(RULE_NEEDS)}")
    _CHECKED.add(needs)
    return needs


#: The ``needs`` sets already checked (a rule's own, a handful per process).
_CHECKED: set[frozenset[str]] = set()
