"""The collectors of ``rtaw-train``: worker processes on this machine, or Ray actors.

:func:`build_collector` returns a :class:`Collection` over the configured backend:

* ``collector.backend=local``: one TorchRL ``Collector`` (``collector.workers=1``) or a
  ``MultiSyncCollector`` over ``collector.workers`` processes;
* ``collector.backend=ray``: a TorchRL ``RayCollector`` with ``collector.workers`` actors
  on a Ray cluster (``collector.ray.*``), each stepping its own ``BatchedWarehouseEnv``
  of ``collector.envs_per_worker`` simulators, all sending their share of every batch
  (``sync=True``), so that a batch is exactly ``algo.frames_per_batch`` frames.

Either way the learner stays in this process and the collectors act on CPUs; when the
learner is on a GPU they act with a CPU copy of the actor, refreshed at every sync.
"""

from __future__ import annotations

import copy
import math
import os
import signal
import socket
import sys
import tempfile
import threading
import time
from collections.abc import Iterable, Iterator
from contextlib import contextmanager
from functools import partial
from typing import Any

import numpy as np

from rtaw_marl.errors import ConfigError, missing_extra

# Without the training extra: one error that names it (errors.missing_extra), no traceback
# of a bare ModuleNotFoundError.
try:
    import torch
    from tensordict import TensorDictBase
    from tensordict.nn import TensorDictModule
    from torchrl.collectors import BaseCollector, Collector, MultiSyncCollector
except ModuleNotFoundError as exc:
    raise missing_extra(exc, __name__, "train") from None

from rtaw_marl.decision.features import FEATURES
from rtaw_marl.envs.mixed import MixedBatchedEnv
from rtaw_marl.envs.torchrl import BatchedWarehouseEnv
from rtaw_marl.scenarios.mix import mix_specs
from rtaw_marl.sim.builder import SimSpec
from rtaw_marl.training.checkpoints import Progress
from rtaw_marl.training.config import RayConfig, TrainConfig
from rtaw_marl.training.interop import make_interop_env
from rtaw_marl.utils.signals import STOP_SIGNALS

__all__ = ["Collection", "build_collector", "learner_device"]


def learner_device(name: str) -> torch.device:
    """The device of ``device=auto|cpu|cuda`` (``auto``: CUDA when torch finds a GPU).

    Raises:
        ConfigError: ``cuda`` was asked for and torch finds no GPU.
    """
    if name == "auto":
        return torch.device("cuda" if torch.cuda.is_available() else "cpu")
    if name == "cuda" and not torch.cuda.is_available():
        raise ConfigError("device=cuda but torch finds no CUDA device; use device=auto or cpu")
    return torch.device(name)


class Collection:
    """Batches from the collectors, on the learner's device, and weight sync back.

    Args:
        collector: The TorchRL collector.
        policy: What the collector acts with: ``actor`` itself, or its CPU copy when
            the learner is on a GPU.
        actor: The learner's actor.
        device: The learner's device.
        cluster: The Ray connection this run opened (closed by :meth:`shutdown`).
    """

    def __init__(
        self,
        collector: BaseCollector,
        policy: TensorDictModule,
        actor: TensorDictModule,
        device: torch.device,
        cluster: RayCluster | None = None,
    ) -> None:
        self.collector = collector
        self.policy, self.actor, self.device = policy, actor, device
        self.cluster = cluster

    def __iter__(self) -> Iterator[TensorDictBase]:
        for data in self.collector:
            yield data if self.device.type == "cpu" else data.to(self.device)

    def sync(self) -> None:
        """Send the learner's current weights to every collector."""
        if self.policy is not self.actor:
            self.policy.load_state_dict(self.actor.state_dict())
        self.collector.update_policy_weights_()

    def shutdown(self) -> None:
        """Stop the collectors (worker processes or actors), then leave the cluster."""
        try:
            self.collector.shutdown()
        finally:
            if self.cluster is not None:
                self.cluster.close()


def build_collector(
    cfg: TrainConfig,
    spec: SimSpec,
    actor: TensorDictModule,
    device: torch.device,
    progress: Progress,
    keys: Iterable[str] = FEATURES,
) -> Collection:
    """The collectors of ``cfg.collector`` for the run at ``progress``.

    Env seeds depend on the resume point, so that a resumed run sees new episodes. The
    batched envs compute the observation entries ``keys`` only (what the networks read).

    Raises:
        ConfigError: Ray is not installed, or its cluster cannot be reached or lacks the
            CPUs the actors need (``backend=ray``).
    """
    col = cfg.collector
    iteration = progress.iteration
    seeds = [cfg.seed * 1009 + 31 * w + iteration for w in range(col.workers)]
    if cfg.interop:
        make_env = [partial(make_interop_env, spec, seed) for seed in seeds]
    else:
        threads = 1 if col.workers > 1 or col.backend == "ray" else None
        members = [(spec, col.envs_per_worker)]
        if cfg.mix:
            share = col.envs_per_worker // len(cfg.mix)
            members = [(member, share) for member in mix_specs(cfg.mix)]
        make_env = [
            partial(_worker_env, members, seed, threads, tuple(keys), cfg.candidates)
            for seed in seeds
        ]
    batch = cfg.algo.frames_per_batch
    remaining = max(cfg.frames - progress.frames, batch)
    kwargs = {"frames_per_batch": batch, "total_frames": -(-remaining // batch) * batch}
    policy = actor if device.type == "cpu" else copy.deepcopy(actor).cpu()
    cluster = None
    if col.backend == "ray":
        cluster = RayCluster(col.ray, col.workers)
        collector = cluster.collector(make_env, policy, kwargs)
    elif col.workers == 1:
        collector = Collector(make_env[0], policy, auto_register_policy_transforms=False, **kwargs)
    else:
        collector = MultiSyncCollector(
            make_env, policy, auto_register_policy_transforms=False, **kwargs
        )
    collector.set_seed(cfg.seed + iteration)
    return Collection(collector, policy, actor, device, cluster)


def _worker_env(
    members: list[tuple[SimSpec, int]],
    seed: int,
    threads: int | None,
    keys: tuple[str, ...] = FEATURES,
    candidates: int | None = None,
) -> BatchedWarehouseEnv | MixedBatchedEnv:
    """The batched env of one collector: ``count`` simulators of each ``(spec, count)``
    member (one member: a :class:`BatchedWarehouseEnv`, each decision's ``candidates``
    nearest tasks when set; a mix: a :class:`MixedBatchedEnv`). A worker process or
    actor runs its policy on ``threads`` threads (torch's default, one per core,
    oversubscribes the cores the workers share).

    Worker processes ignore Ctrl-C and SIGTERM: the terminal and schedulers signal the
    whole process group, and the main process alone must handle them (save, then shut
    the workers down); a worker killed by SIGTERM leaks its semaphores.
    """
    if threads is not None:
        torch.set_num_threads(threads)
        if threading.current_thread() is threading.main_thread():
            for signum in STOP_SIGNALS:
                signal.signal(signum, signal.SIG_IGN)
    if len(members) == 1:
        return BatchedWarehouseEnv(*members[0], seed, keys, candidates)
    return MixedBatchedEnv(members, seed, keys)


# --------------------------------------------------------------------------- ray
class ActorCollector(Collector):
    """The collector inside a Ray actor."""

    def set_seed(self, seed: int, static_seed: bool = False) -> int:
        """Seed the env, then the actor's torch and numpy as a local worker process
        seeds its own (the policy samples from torch's global generator): a run gives the
        same batches on both backends."""
        new_seed = super().set_seed(seed, static_seed)
        torch.manual_seed(seed)
        np.random.seed(seed)  # noqa: NPY002  (what torchrl's worker processes do)
        return new_seed

    def __repr__(self) -> str:
        # Ray prefixes an actor's output with its repr; Collector's spans dozens of lines.
        return "collector"


class RayCluster:
    """This run's connection to Ray: starts a local cluster or joins one, checks that
    the actors' CPUs are free, and leaves (or stops a local cluster) on :meth:`close`.

    Inside a Ray job (a sweep on Hydra's Ray launcher) Ray is already initialised: the
    actors join the job's cluster, and :meth:`close` leaves it running.

    Raises:
        ConfigError: Ray is not installed; the address does not answer within
            ``connect_timeout_s``; the cluster lacks the CPUs the actors need.
    """

    def __init__(self, cfg: RayConfig, actors: int) -> None:
        try:
            import ray
        except ModuleNotFoundError:
            raise ConfigError(
                "collector.backend=ray needs Ray (not installed): pip install 'rtaw_marl[ray]'"
            ) from None
        self.cfg, self.actors, self.owned = cfg, actors, False
        need = actors * cfg.cpus_per_actor
        if not ray.is_initialized():
            # Ray's own notes (token authentication, ...) would bury the run's lines.
            options: dict[str, Any] = {"logging_level": "error", "include_dashboard": False}
            joining = cfg.address != "local"
            if joining:
                _check_reachable(cfg.address, cfg.connect_timeout_s)
            else:
                # At least the CPUs the actors reserve, as local worker processes would.
                options["num_cpus"] = max(os.cpu_count() or 1, math.ceil(need))
            try:
                with _connecting(joining, cfg.connect_timeout_s):
                    ray.init(address=cfg.address, **options)
            except (ConnectionError, RuntimeError, ValueError) as exc:
                raise ConfigError(
                    f"collector.ray.address={cfg.address}: {str(exc).splitlines()[0]} "
                    f"(within {cfg.connect_timeout_s:g} s)"
                ) from None
            self.owned = True
        # Ray would wait for the CPUs forever; fail instead, after a grace period for
        # CPUs that are being released (the actors of a run that just ended).
        total = ray.cluster_resources().get("CPU", 0.0)
        deadline = time.monotonic() + cfg.connect_timeout_s
        while (free := ray.available_resources().get("CPU", 0.0)) < need <= total:
            if time.monotonic() > deadline:
                break
            time.sleep(0.1)
        if need > free:
            self.close()
            raise ConfigError(
                f"collector.workers={actors} Ray actors x collector.ray.cpus_per_actor="
                f"{cfg.cpus_per_actor:g} need {need:g} CPUs; the Ray cluster has {free:g} "
                f"free of {total:g}"
            )

    def collector(self, make_env: list, policy: TensorDictModule, kwargs: dict) -> BaseCollector:
        """A synchronous ``RayCollector``: every batch holds each actor's equal share."""
        from torchrl.collectors.distributed import RayCollector

        collector = RayCollector(
            make_env,
            policy,
            collector_class=ActorCollector,
            collector_kwargs={"auto_register_policy_transforms": False},
            remote_configs={"num_cpus": self.cfg.cpus_per_actor, "num_gpus": 0},
            sync=True,
            **kwargs,
        )
        collector.update_policy_weights_()  # connects the weight sync before the first batch
        return collector

    def close(self) -> None:
        """Leave the cluster (a local one stops with it) if this run joined it."""
        import ray

        if self.owned and ray.is_initialized():
            ray.shutdown()
        self.owned = False


@contextmanager
def _connecting(joining: bool, timeout_s: float) -> Iterator[None]:
    """While ``ray.init`` joins a cluster: give up after about ``timeout_s`` (Ray retries
    for 20 s or more where something else answers at the address), and hold what Ray's
    C++ core writes on stderr meanwhile (a warning per retry would bury the one-line
    error); what it wrote is shown if the connection succeeds."""
    if not joining:
        yield
        return
    key = "RAY_gcs_server_port_wait_time_s"  # Ray's connection attempts, ~1 s each
    before = os.environ.get(key)
    os.environ[key] = str(max(1, math.ceil(timeout_s)))
    sys.stderr.flush()
    saved = os.dup(2)
    with tempfile.TemporaryFile() as held:
        os.dup2(held.fileno(), 2)
        joined = False
        try:
            yield
            joined = True
        finally:
            os.dup2(saved, 2)
            os.close(saved)
            if before is None:
                os.environ.pop(key, None)
            else:
                os.environ[key] = before
            held.seek(0)
            text = held.read().decode(errors="replace")
            if joined and text:
                sys.stderr.write(text)


def _check_reachable(address: str, timeout_s: float) -> None:
    """Fail fast when the head at ``HOST:PORT`` (or ``ray://HOST:PORT``) does not answer;
    ``ray.init`` would keep retrying for a minute or more."""
    if address == "auto":
        return  # Ray finds the local cluster's address itself, or fails at once
    hostport = address.removeprefix("ray://")
    host, _, port = hostport.rpartition(":")
    if not host or not port.isdigit():
        raise ConfigError(
            f"collector.ray.address must be local, auto, HOST:PORT or ray://HOST:PORT, "
            f"got {address!r}"
        )
    try:
        socket.create_connection((host.strip("[]"), int(port)), timeout=timeout_s).close()
    except OSError as exc:
        reason = "timed out" if isinstance(exc, TimeoutError) else exc.strerror or str(exc)
        raise ConfigError(
            f"collector.ray.address={address}: no Ray head answers there ({reason} after "
            f"at most {timeout_s:g} s); start one with `ray start --head --port={port}`"
        ) from None
