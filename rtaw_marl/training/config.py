"""Typed options of ``rtaw-train``: the PPO algorithm, the collector, the periodic
evaluation on the selection seeds (``selection``), and the whole run. Plain Python (no
torch), registered with Hydra by :mod:`rtaw_marl.config.store`.

``selection`` was called ``eval`` before (a word ``rtaw-eval`` keeps for itself), and
``sim`` (the simulator's keys, as in every command) ``env``: the shipped checkpoints and
older runs record ``eval`` and ``env`` sections in their ``config`` and ``eval.*`` and
``env.*`` overrides in their ``command``. :func:`upgrade_config` and
:func:`upgrade_command` read those under today's names; :func:`renamed_key` names the new
key of an old one typed on the command line (:mod:`rtaw_marl.utils.renamed`)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from rtaw_marl.errors import ConfigError
from rtaw_marl.policies.config import SearchConfig
from rtaw_marl.sim.builder import SimGroups
from rtaw_marl.sim.inputs import SELECTION_SEEDS, seed_list, seed_value
from rtaw_marl.training.loggers.config import logger_option
from rtaw_marl.utils import renamed
from rtaw_marl.utils.checks import at_least, check_fields, check_number

__all__ = [
    "CollectorConfig",
    "ImitationConfig",
    "PPOConfig",
    "RayConfig",
    "SelectionConfig",
    "TrainConfig",
    "renamed_key",
    "upgrade_command",
    "upgrade_config",
]

#: Values of ``device`` (the learner's).
DEVICES = ("auto", "cpu", "cuda")

#: The largest ``frames``: steps are logged as floats, exact up to 2**53.
MAX_FRAMES = 2**53

#: What an imitation warm start can learn from: a rule (``hindsight`` sees the future),
#: ``best`` (the setting's best rule on the selection seeds, as the run's evaluator
#: chooses it), or ``search`` with a network (by default the one being trained: expert
#: iteration).
TEACHERS = (
    "lookahead", "hungarian", "batch", "mpdm", "rbts", "hindsight", "best", "search",
)  # fmt: skip


@dataclass(kw_only=True)
class PPOConfig:
    """PPO (the ``algo`` group). The defaults are tuned for throughput on a CPU
    (``algo=ppo``, docs/training.md); ``algo=ppo_paper`` is the paper's table.

    Attributes:
        lr: Adam learning rate (paper: 3e-4).
        frames_per_batch: Frames per update (the paper's "update interval": 512).
        epochs: Passes over each batch (paper: 16).
        minibatch_size: Minibatch size (not in the paper's table; its code used 32).
        gamma: Discount.
        lmbda: GAE lambda.
        clip_epsilon: PPO clipping.
        entropy_coeff_start: Entropy coefficient at the start, annealed linearly
            (paper: 0.01 -> 0.001).
        entropy_coeff_end: Entropy coefficient at the end.
        critic_coeff: Value-function coefficient (paper: 0.0002).
        policy_coeff: Policy-loss coefficient (paper: 0.02, which against an entropy
            coefficient of 0.01 keeps the policy near uniform for long).
        max_grad_norm: Gradient clipping (max global norm).
        normalize_advantage: Standardise advantages per minibatch (the original code did).
        reward_scale: Rewards are multiplied by this before GAE; ``None`` means
            1 / layout scale.
    """

    lr: float = 1.0e-3
    frames_per_batch: int = 8192
    epochs: int = 4
    minibatch_size: int = 2048
    gamma: float = 0.99
    lmbda: float = 0.95
    clip_epsilon: float = 0.2
    entropy_coeff_start: float = 0.01
    entropy_coeff_end: float = 0.001
    critic_coeff: float = 0.0002
    policy_coeff: float = 1.0
    max_grad_norm: float = 0.5
    normalize_advantage: bool = True
    reward_scale: float | None = None

    def __post_init__(self) -> None:
        check_fields(self, "algo.")
        at_least(self, "algo.", 1, "frames_per_batch", "epochs", "minibatch_size")
        for key in ("lr", "clip_epsilon", "max_grad_norm"):
            check_number(f"algo.{key}", getattr(self, key), above=0)
        for key in ("gamma", "lmbda"):
            value = getattr(self, key)
            if not 0 <= value <= 1:
                raise ConfigError(f"algo.{key} must lie in [0, 1], got {value}")
        for key in ("entropy_coeff_start", "entropy_coeff_end", "critic_coeff", "policy_coeff"):
            check_number(f"algo.{key}", getattr(self, key), minimum=0)
        if self.reward_scale is not None:
            check_number("algo.reward_scale", self.reward_scale, above=0)


@dataclass(kw_only=True)
class RayConfig:
    """The Ray cluster of ``collector.backend=ray`` (``collector.ray.*``; docs/cluster.md).

    Attributes:
        address: ``local`` starts a Ray cluster on this machine for the run and stops it
            at the end; ``auto`` joins the cluster started on this machine by ``ray start
            --head``; ``HOST:PORT`` joins the cluster whose head listens there;
            ``ray://HOST:PORT`` connects through Ray Client. Inside a Ray job (Hydra's Ray
            launcher) the job's own cluster is used.
        cpus_per_actor: CPUs Ray reserves for each collector actor (fractions allowed).
        connect_timeout_s: Seconds to wait for the cluster's head to answer.
    """

    address: str = "local"
    cpus_per_actor: float = 1.0
    connect_timeout_s: float = 10.0

    def __post_init__(self) -> None:
        check_fields(self, "collector.ray.")
        if not self.address.strip():
            raise ConfigError("collector.ray.address must be local, auto or HOST:PORT")
        for key in ("cpus_per_actor", "connect_timeout_s"):
            check_number(f"collector.ray.{key}", getattr(self, key), above=0)


#: Where ``collector.backend`` runs the collectors.
BACKENDS = ("local", "ray")


@dataclass(kw_only=True)
class CollectorConfig:
    """How frames are collected (``collector.*``; ``collector=ray`` sets the backend).

    Attributes:
        backend: ``local``: worker processes on this machine; ``ray``: Ray actors on a
            cluster (``collector.ray.*``), the learner stays in this process.
        workers: Collectors: worker processes (``local``; a multi-process collector when
            > 1) or Ray actors (``ray``).
        envs_per_worker: Simulators per worker or actor, stepped as one batched env.
        ray: The Ray cluster (``backend=ray`` only).
    """

    backend: str = "local"
    workers: int = 1
    envs_per_worker: int = 64
    ray: RayConfig = field(default_factory=RayConfig)

    def __post_init__(self) -> None:
        check_fields(self, "collector.")
        at_least(self, "collector.", 1, "workers", "envs_per_worker")
        if self.backend not in BACKENDS:
            raise ConfigError(
                f"collector.backend must be one of {', '.join(BACKENDS)}, got {self.backend!r}"
            )


#: What ``selection.metric`` may select on.
SELECTION_METRICS = ("ttd", "tasks_finished")


@dataclass(kw_only=True)
class SelectionConfig:
    """Greedy evaluation during training on the selection seeds, which picks ``best.pt``
    (``selection.*``; ``eval.*`` before).

    Attributes:
        every_frames: Evaluate against MPDM every this many frames.
        seeds: Selection seeds (1000-1009), played in lockstep; at least 1000 (an error
            otherwise): the evaluation seeds 0-19 are never used for training or
            selection.
        keep: Also keep the ``keep`` best evaluations' checkpoints (weights only) in
            ``checkpoints/top/<frames>.pt``: the candidates of a second selection stage
            on fresh selection seeds (:mod:`rtaw_marl.training.selection`), which picks
            among them without the first stage's winner's curse. 1: ``best.pt`` alone.
        metric: What picks the checkpoints: ``ttd`` (least mean TTD: the paper's
            objective) or ``tasks_finished`` (most tasks finished: LoRR's, for horizon
            episodes, where a policy that finishes more tasks also travels more).
    """

    every_frames: int = 204_800
    seeds: list[int] = field(default_factory=lambda: list(range(1000, 1010)))
    keep: int = 1
    metric: str = "ttd"

    def __post_init__(self) -> None:
        check_fields(self, "selection.")
        at_least(self, "selection.", 1, "every_frames", "keep")
        if self.metric not in SELECTION_METRICS:
            raise ConfigError(
                f"selection.metric must be one of {', '.join(SELECTION_METRICS)}, "
                f"got {self.metric!r}"
            )
        if not self.seeds:
            raise ConfigError("selection.seeds must name at least one seed")
        low = [s for s in seed_list(self.seeds, "selection.seeds") if s < SELECTION_SEEDS]
        if low:
            raise ConfigError(
                f"selection.seeds {low[:5]} are below {SELECTION_SEEDS}: selection seeds start at "
                f"{SELECTION_SEEDS}; seeds 0-{SELECTION_SEEDS - 1} are kept for evaluation, "
                "which must not choose checkpoints"
            )


#: The old name of :class:`SelectionConfig` (deprecated; the key was ``eval``).
TrainEvalConfig = SelectionConfig

#: Sections of ``rtaw-train``'s config renamed since: old name -> new name, and what the
#: new one is (the one-line error for an old key, :func:`renamed_key`): every command's
#: (``env`` -> ``sim``, :data:`rtaw_marl.utils.renamed.RENAMED`) and its own.
RENAMED = {
    **renamed.RENAMED,
    "eval": ("selection", "the selection seeds' evaluation during training"),
}


def renamed_key(key: str) -> str | None:
    """The one-line error for a key of ``rtaw-train`` that was renamed (``eval.seeds``:
    ``eval.seeds is now selection.seeds (...)``; ``env.num_robots``: ``env.num_robots is
    now sim.num_robots (...)``); ``None`` for any other key."""
    return renamed.renamed_key(key, RENAMED)


def upgrade_config(config: Mapping[str, Any]) -> dict[str, Any]:
    """A stored training config (a checkpoint's ``config``) under today's names: an old
    ``eval`` section is ``selection``, an old ``env`` section ``sim`` (the shipped
    checkpoints and older runs say ``eval`` and ``env``). A config already under today's
    names comes back as it was (a copy)."""
    return renamed.upgrade_config(config, RENAMED)


def upgrade_command(command: Sequence[str]) -> list[str]:
    """A recorded command (a checkpoint's ``command``) spelled with today's keys:
    ``eval.every_frames=40960`` is ``selection.every_frames=40960``,
    ``env.num_robots=10`` is ``sim.num_robots=10``; anything else is kept as it was."""
    return renamed.upgrade_command(command, RENAMED)


@dataclass(kw_only=True)
class ImitationConfig:
    """An optional warm start by imitation before PPO (``imitation.*``;
    :mod:`rtaw_marl.training.imitation`).

    Attributes:
        teacher: A rule (``lookahead``, ``hungarian``, ``batch``, ``mpdm``, ``rbts``,
            or ``hindsight``, which sees the future; the ``baselines`` defaults),
            ``best``: the best of the five online rules on the selection seeds, which
            the run plays anyway (the bar of its curve and verdict), or ``search``:
            the search of :mod:`rtaw_marl.policies.search` over the network being
            trained, as it is at each round's start (expert iteration: each round's
            search is guided by the previous round's network), or over the fixed
            ``imitation.search.policy`` when set; ``None``: no warm start.
        frames: Teacher-labelled decisions in all rounds together (not counted in
            ``frames``, which counts PPO's).
        rounds: Round 0 follows the teacher; rounds 1.. follow the student (DAgger).
        epochs: Passes over everything labelled so far after each round.
        minibatch_size: Decisions per gradient step.
        lr: Adam learning rate of the warm start.
        search: The search teacher's width, horizon and leaf weight (and the network
            it searches, when not the one being trained).
    """

    teacher: str | None = None
    frames: int = 131_072
    rounds: int = 4
    epochs: int = 4
    minibatch_size: int = 1024
    lr: float = 1.0e-3
    search: SearchConfig = field(default_factory=SearchConfig)

    def __post_init__(self) -> None:
        check_fields(self, "imitation.")
        if self.teacher is not None and self.teacher not in TEACHERS:
            raise ConfigError(
                f"imitation.teacher must be one of {', '.join(TEACHERS)} or null, "
                f"got {self.teacher!r}"
            )
        for key in ("frames", "rounds", "epochs", "minibatch_size"):
            value = getattr(self, key)
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise ConfigError(f"imitation.{key} must be an integer >= 1, got {value!r}")
        if not self.lr > 0:
            raise ConfigError(f"imitation.lr must be > 0, got {self.lr!r}")


@dataclass(kw_only=True)
class TrainConfig(SimGroups):
    """A whole ``rtaw-train`` run.

    Attributes:
        model: A model option (:class:`~rtaw_marl.models.config.RTAWConfig`).
        algo: The PPO settings.
        seed: Seed of the whole run (networks, sampling, episodes).
        frames: Total frames (decisions) to collect: a whole number of batches of
            ``algo.frames_per_batch``, never rounded (the paper's budget, 4M, in whole
            batches of 8192 and of 512: 4,005,888).
        torch_threads: torch intra-op threads of the learner and the in-process
            collector (1 is fastest for the paper's network; RTAW+'s update runs 1.7x
            faster with 2 on two cores, docs/performance.md).
        device: Where the learner updates the networks: ``auto`` (``cuda`` when torch
            finds a GPU, else ``cpu``), ``cpu`` or ``cuda``. Collection and evaluation
            run on CPUs.
        collector: Collection settings.
        selection: The periodic greedy evaluation on the selection seeds, which picks
            the checkpoints (``eval`` before).
        imitation: The optional warm start by imitation.
        logger: Where the scalars go: a ``logger`` option (``csv``, ``tensorboard``,
            ``mlflow``, ``wandb``, ``none``; :mod:`rtaw_marl.training.loggers.config`) or
            its name.
        resume: A checkpoint to continue from (``last.pt``). It must hold the same
            scenario (sim, layout, navigator, tasks, selection seeds) and fewer frames
            than ``frames``.
        resume_new_scenario: Allow ``resume`` from a checkpoint of another scenario: its
            networks continue here, its best TTD and evaluation history are dropped
            (they were measured on the other scenario).
        output_dir: The run folder; ``None`` means the Hydra run folder.
        progress: Show a tqdm progress bar.
        interop: Train through TorchRL's PettingZooWrapper on the AEC env (small M).
        mix: Train on several scenarios at once (a generalist): member scenarios, each
            ``NAME`` or ``NAME:m30:n5:t200:paper:s90:random`` (robots, queue slots, tasks,
            episode mode, generated layout size, task stream changed;
            :mod:`rtaw_marl.scenarios.mix`); every collector's batch holds
            ``collector.envs_per_worker / len(mix)`` simulators of each. Empty: the run's
            own scenario alone. The run's scenario still picks the checkpoints
            (``selection.*``). Needs ``model=rtaw_plus`` with ``model.fleet_summary=true``
            (or ``model.critic_fleet=false``).
        init_actor: Start the actor from the actor of this checkpoint file or shipped
            policy name (its weights only: the critic, the optimizer and the run's
            progress start fresh), e.g. a specialist continued on a mix. Its network must
            be this run's (``model.name``, ``embed_dim``, ``heads``); ignored on resume.
        candidates: Train and select on each decision's ``K`` queued tasks nearest the
            free robot (the network's inputs and actions; evaluate the checkpoint with
            ``candidates=K``): LoRR's windows hold ``1.5 M`` tasks, too many for the
            network's attention over all of them. ``None``: every queued task. Not with
            ``mix``, ``interop`` or an imitation warm start.
        verdict: End by playing ``best.pt`` and the setting's best rule (the best on the
            selection seeds) on the evaluation seeds 0-19, which nothing in the run
            chose on: the last line says whether the checkpoint beats the rule, with the
            paired difference's 95% interval (``verdict.json`` in the run folder;
            :mod:`rtaw_marl.training.verdict`). Costs 20 episodes of each.
    """

    model: Any
    algo: PPOConfig = field(default_factory=PPOConfig)
    seed: int = 0
    frames: int = 4_005_888
    torch_threads: int = 1
    device: str = "auto"
    collector: CollectorConfig = field(default_factory=CollectorConfig)
    selection: SelectionConfig = field(default_factory=SelectionConfig)
    imitation: ImitationConfig = field(default_factory=ImitationConfig)
    logger: Any = "csv"
    resume: str | None = None
    resume_new_scenario: bool = False
    output_dir: str | None = None
    progress: bool = True
    interop: bool = False
    mix: list[str] = field(default_factory=list)
    init_actor: str | None = None
    candidates: int | None = None
    verdict: bool = True

    def __post_init__(self) -> None:
        check_fields(self)
        self._check_mix()
        self._check_candidates()
        seed_value(self.seed, "seed")
        at_least(self, "", 1, "frames", "torch_threads")
        if self.device not in DEVICES:
            raise ConfigError(f"device must be one of {', '.join(DEVICES)}, got {self.device!r}")
        self.logger = logger_option(self.logger)
        self._check_budgets()

    def _check_candidates(self) -> None:
        if self.candidates is None:
            return
        at_least(self, "", 1, "candidates")
        clash = [
            key for key, on in (("mix", bool(self.mix)), ("interop", self.interop),
                                ("imitation.teacher", self.imitation.teacher is not None))
            if on
        ]  # fmt: skip
        if clash:
            raise ConfigError(f"candidates= does not work with {clash[0]} yet; leave one out")

    def _check_mix(self) -> None:
        if not self.mix:
            return
        from rtaw_marl.scenarios.mix import mix_specs

        mix_specs(self.mix)  # names, keys and values
        model = self.model
        fleet = getattr(model, "critic_fleet", None)
        if getattr(model, "name", None) != "rtaw_plus" or (
            fleet and not getattr(model, "fleet_summary", False)
        ):
            raise ConfigError(
                "mix= stacks simulators with different fleets, so the networks must not "
                "read the whole fleet: use model=rtaw_plus with model.fleet_summary=true "
                "(or model.critic_fleet=false)"
            )
        if self.interop:
            raise ConfigError("mix= runs batched envs: set interop=false")
        if self.collector.envs_per_worker % len(self.mix):
            raise ConfigError(
                f"collector.envs_per_worker={self.collector.envs_per_worker} must be a "
                f"multiple of the {len(self.mix)} mix members (each gets the same share)"
            )

    def _check_budgets(self) -> None:
        """Budgets are spent in whole units, never rounded: ``frames`` in batches of
        ``algo.frames_per_batch`` (after the checkpoint's frames, on resume);
        ``imitation.frames`` in rounds of one decision per
        simulator (``imitation.rounds x collector.envs_per_worker``)."""
        batch = self.algo.frames_per_batch
        if self.frames < batch:
            raise ConfigError(f"frames={self.frames} is less than one batch ({batch})")
        if self.frames > MAX_FRAMES:
            raise ConfigError(
                f"frames={self.frames} is more than 2**53 = {MAX_FRAMES}: frame counts past "
                "it are not exact in the logs' steps"
            )
        if self.resume is None:  # a resume counts from its checkpoint (checkpoints.resume)
            _whole_units("frames", self.frames, batch, "batches of algo.frames_per_batch")
        if self.imitation.teacher is not None:
            unit = self.imitation.rounds * self.collector.envs_per_worker
            _whole_units(
                "imitation.frames", self.imitation.frames, unit,
                "imitation.rounds x collector.envs_per_worker",
            )  # fmt: skip


def _whole_units(key: str, value: int, unit: int, what: str) -> None:
    """Refuse a budget ``value`` that is not a whole number of ``unit``s, naming the
    nearest valid values.

    Raises:
        ConfigError: ``key=value is not a multiple of <what> = unit: use a or b``.
    """
    if value % unit:
        low = value // unit * unit
        nearest = f"{low} or {low + unit}" if low else f"{unit}"
        raise ConfigError(
            f"{key}={value} is not a whole number of {what} = {unit} (it is never "
            f"rounded): use {nearest}"
        )
