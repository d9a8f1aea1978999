"""Task-stream options (the ``tasks`` config group)."""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass, field
from typing import Any, ClassVar

from rtaw_marl.errors import ConfigError
from rtaw_marl.sim.lorr import LoRRTasks, read_problem
from rtaw_marl.sim.options.base import Option
from rtaw_marl.sim.tasks import (
    POC_TASKS,
    TWO_TASKS,
    ClusteredTasks,
    DesignatedTasks,
    FixedTasks,
    RandomTasks,
    StationTasks,
    TaskStream,
    load_task_csv,
)
from rtaw_marl.utils.checks import at_least, check_number, check_value

__all__ = [
    "TASK_STREAMS",
    "ClusteredTasksConfig",
    "DesignatedTasksConfig",
    "FileTasksConfig",
    "GivenTasks",
    "LoRRTasksConfig",
    "PocTasksConfig",
    "RandomTasksConfig",
    "StationTasksConfig",
    "TaskOption",
    "TwoTaskConfig",
]


@dataclass(kw_only=True)
class TaskOption(Option, ABC):
    """A task-stream option."""

    group: ClassVar[str] = "tasks"

    @abstractmethod
    def build(self) -> TaskStream:
        """The task stream this option describes."""


@dataclass(kw_only=True)
class RandomTasksConfig(TaskOption):
    """Origin and destination uniform over the free cells."""

    name: str = "random"

    def build(self) -> TaskStream:
        return RandomTasks()


@dataclass(kw_only=True)
class DesignatedTasksConfig(TaskOption):
    """Gaussian pickup and delivery regions around fixed centres.

    Attributes:
        pickup_centres: ``[x, y]`` centres of the pickup regions, cells of the layout used
            as given (a centre off the layout is an error). ``null``: the original RTAW
            code's five centres (11,10), (29,29), (48,16), (48,29), (4,54), written for
            its 60x60 area. They stay as written along a side of 60 to 64 cells (the
            60x60 layouts and the 64x64 maps they were made for); along any other side
            they are scaled in proportion, ``x' = (x + 0.5) * W / 60 - 0.5`` (likewise
            ``y`` with ``H``), and a scaled centre off the main region moves to its
            nearest main-region cell, so tasks spread over the whole map (on the 161x63
            ``warehouse-10-20-10-2-1.map`` the centres' x runs from 12 to 130, not 4 to 48).
        delivery_centres: ``[x, y]`` centres of the delivery regions; ``null``: the
            default centres, placed like the pickups'.
        sigma: Standard deviation of every region, in cells (not scaled).
    """

    name: str = "designated"
    # list[Any], checked below as [[x, y], ...] of numbers: OmegaConf 2.3 refuses an
    # integer in a nested list[list[float]] (`tasks.pickup_centres=[[10,20]]`).
    pickup_centres: list[Any] | None = None
    delivery_centres: list[Any] | None = None
    sigma: float = 5.0

    def __post_init__(self) -> None:
        super().__post_init__()
        check_number("tasks.sigma", self.sigma, above=0)
        for key in ("pickup_centres", "delivery_centres"):
            centres = getattr(self, key)
            if centres is None:
                continue
            check_value(f"tasks.{key}", centres, list[list[float]])
            if not centres or any(len(c) != 2 for c in centres):
                raise ConfigError(
                    f"tasks.{key} must be a non-empty list of [x, y] pairs, got {centres}"
                )

    def build(self) -> TaskStream:
        return DesignatedTasks(self.pickup_centres, self.delivery_centres, self.sigma)


@dataclass(kw_only=True)
class ClusteredTasksConfig(TaskOption):
    """Tasks around cluster centres drawn per episode on free cells.

    Attributes:
        num_clusters: Number of clusters.
        sigma: Standard deviation of every cluster, in cells.
    """

    name: str = "clustered"
    num_clusters: int = 5
    sigma: float = 4.0

    def __post_init__(self) -> None:
        super().__post_init__()
        at_least(self, "tasks.", 1, "num_clusters")
        check_number("tasks.sigma", self.sigma, above=0)

    def build(self) -> TaskStream:
        return ClusteredTasks(self.num_clusters, self.sigma)


@dataclass(kw_only=True)
class StationTasksConfig(TaskOption):
    """Pickup at the layout's pickup stations, delivery at its delivery stations (needs a
    generated warehouse layout: ``layout=A``..``E`` or ``warehouse``)."""

    name: str = "stations"

    def build(self) -> TaskStream:
        return StationTasks()


@dataclass(kw_only=True)
class FileTasksConfig(TaskOption):
    """A fixed task list: CSV with header ``ox,oy,dx,dy``, one task per row in arrival order.

    Attributes:
        path: The CSV file (required; ``builtin:NAME`` is resolved like every input
            path, though no task CSV is shipped).
    """

    name: str = "file"
    path: str = field()  # required: no default

    def build(self) -> TaskStream:
        return load_task_csv(self.path)


@dataclass(kw_only=True)
class LoRRTasksConfig(TaskOption):
    """A League of Robot Runners 2024 problem's tasks (file order, cycled) and start
    cells (:mod:`rtaw_marl.sim.lorr`); ``scenario=lorr`` sets the rest.

    Attributes:
        problem: The problem JSON (required), or ``builtin:random_32_32_20_100.json``,
            the shipped one.
        starts: ``file`` (the first ``sim.num_robots`` cells of its agent file) or
            ``random`` (distinct random free cells per seed, for more robots).
    """

    name: str = "lorr"
    problem: str | None = None
    starts: str = "file"

    def __post_init__(self) -> None:
        if self.starts not in ("file", "random"):
            raise ConfigError(f"tasks.starts must be one of file, random, got {self.starts!r}")

    def build(self) -> TaskStream:
        if self.problem is None:
            raise ConfigError("tasks=lorr needs tasks.problem=FILE.json (a LoRR problem)")
        return LoRRTasks(read_problem(self.problem), self.starts)


@dataclass(kw_only=True)
class PocTasksConfig(TaskOption):
    """The paper's proof-of-concept list of 5 tasks (appendix)."""

    name: str = "poc"

    def build(self) -> TaskStream:
        return FixedTasks(POC_TASKS, name="poc tasks")


@dataclass(kw_only=True)
class TwoTaskConfig(TaskOption):
    """The paper's two-task setting: the queue always holds (0,0)->(3,3) and (0,0)->(9,9)."""

    name: str = "two_task"

    def build(self) -> TaskStream:
        return FixedTasks(TWO_TASKS, refill_same_slot=True, name="two-task tasks")


@dataclass(kw_only=True)
class GivenTasks(TaskOption):
    """A :class:`TaskStream` built in Python (not a Hydra option: it is not serializable)."""

    name: str = "given"
    stream: TaskStream

    def build(self) -> TaskStream:
        return self.stream


TASK_STREAMS: dict[str, type[TaskOption]] = {
    cls.__dataclass_fields__["name"].default: cls
    for cls in (
        RandomTasksConfig,
        DesignatedTasksConfig,
        ClusteredTasksConfig,
        StationTasksConfig,
        FileTasksConfig,
        LoRRTasksConfig,
        PocTasksConfig,
        TwoTaskConfig,
    )
}
