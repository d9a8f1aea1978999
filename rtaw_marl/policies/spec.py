"""What a policy label stands for, and how to build it: the one policy resolver.

A :class:`PolicySpec` names a policy without building it (it pickles to worker
processes and records in journals): a rule by name with its parameters, a shipped
learned policy, a checkpoint file, either searched at decision time (``search``) or
deciding a timestep's free robots together (``matched``), or a user's ``module:Name``.
``rtaw-eval``, ``rtaw-render``, ``rtaw-view`` and the benchmarks project all resolve
their policies through it.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

from rtaw_marl.errors import ConfigError, unknown_name
from rtaw_marl.policies.config import BaselinesConfig
from rtaw_marl.policies.user import import_policy
from rtaw_marl.sim.core import WarehouseSim

__all__ = ["KINDS", "PolicySpec"]

Kind = Literal["rule", "pretrained", "checkpoint", "search", "matched", "import"]
#: The kinds of policy a label can stand for.
KINDS: tuple[Kind, ...] = ("rule", "pretrained", "checkpoint", "search", "matched", "import")


@dataclass(frozen=True)
class PolicySpec:
    """A policy by name, built on demand.

    Attributes:
        kind: ``"rule"`` (:data:`~rtaw_marl.policies.BASELINES`), ``"pretrained"`` (a
            shipped policy), ``"checkpoint"`` (a file, or a shipped name), ``"search"``
            (a file or shipped name searched at decision time,
            :mod:`rtaw_marl.policies.search`), ``"matched"`` (a file or shipped name
            deciding every free robot of a timestep at once,
            :mod:`rtaw_marl.policies.matched`) or ``"import"`` (``module:Name``,
            :mod:`rtaw_marl.policies.user`).
        name: The rule's or shipped policy's name, the checkpoint path, or the spec.
        params: A rule's parameters (:class:`~rtaw_marl.policies.BaselinesConfig`
            keys), or a search's (``width``, ``horizon``, ``leaf``), as sorted
            ``(key, value)`` pairs.
        candidates: A learned policy's ``candidates=K`` (``None``: every queued task).
    """

    kind: Kind
    name: str
    params: tuple[tuple[str, Any], ...] = ()
    candidates: int | None = None

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise unknown_name("policy kind", self.kind, list(KINDS))

    @classmethod
    def rule(cls, name: str, params: BaselinesConfig | dict[str, Any] | None = None) -> PolicySpec:
        """A rule with parameters, checked now (not in a worker).

        Raises:
            ConfigError: An unknown rule (the message lists them) or parameter.
        """
        from rtaw_marl.policies import BASELINES  # the registry imports this module's peers

        if name not in BASELINES:
            raise unknown_name("rule", name, list(BASELINES))
        values = params if isinstance(params, dict) else vars(params or BaselinesConfig())
        BaselinesConfig(**values)
        return cls("rule", name, tuple(sorted(values.items())))

    def build(
        self,
        sim: WarehouseSim | None = None,
        label: str | None = None,
        torch_threads: int | None = None,
    ) -> Any:
        """The policy: a rule bound to ``sim`` (its distance model, scale and noise, for
        ``act(obs)``; ``act_sim`` needs none), a loaded network, or the user's object.

        Raises:
            ConfigError: A file or name that does not load, or a user policy that does
                not import (one line each).
        """
        if self.kind == "rule":
            from rtaw_marl.policies import make_baseline

            params = BaselinesConfig(**dict(self.params))
            return make_baseline(self.name, env=sim, params=params)
        if self.kind == "import":
            return import_policy(self.name)[1]
        if self.kind == "search":
            from rtaw_marl.policies.search_policy import load_search  # torch

            return load_search(
                self.name, **dict(self.params), name=label, torch_threads=torch_threads,
                candidates=self.candidates,
            )  # fmt: skip
        from rtaw_marl.policies.network import load_policy  # torch: only when needed

        if self.kind == "matched":
            from rtaw_marl.policies.matched import MatchedPolicy

            policy = load_policy(self.name, torch_threads=torch_threads, candidates=self.candidates)
            return MatchedPolicy(policy, name=label)

        # A checkpoint= value is a file or a shipped name: load_policy says which is wrong.
        source = self.name if self.kind == "checkpoint" else self.path()
        return load_policy(
            source, name=label, torch_threads=torch_threads, candidates=self.candidates
        )

    def loads(self) -> str | None:
        """None if the policy can be built, else why not (one line)."""
        if self.kind == "rule":
            return None
        try:
            self.build()
        except (ConfigError, ModuleNotFoundError) as err:
            return " ".join(str(err).split())
        return None

    def path(self) -> Path | None:
        """The file of a learned policy (the checkpoint, or a shipped policy's), whose
        contents an evaluation journal hashes; ``None`` for a rule or a user policy."""
        if self.kind in ("rule", "import"):
            return None
        from rtaw_marl.policies.pretrained.registry import pretrained_path

        if self.kind in ("checkpoint", "search", "matched"):
            # A checkpoint= value that is no file is a shipped name (load_policy's rule).
            path = Path(self.name)
            return path if path.is_file() else pretrained_path(self.name)
        return pretrained_path(self.name)
