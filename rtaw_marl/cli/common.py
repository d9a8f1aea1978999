"""Helpers shared by the command-line entry points."""

from __future__ import annotations

import sys
from collections.abc import Callable
from functools import wraps
from typing import Any

from omegaconf import DictConfig, OmegaConf
from omegaconf.errors import OmegaConfBaseException

from rtaw_marl.errors import ConfigError, RtawError
from rtaw_marl.evaluation.evaluate import SimPolicy
from rtaw_marl.policies import make_baseline
from rtaw_marl.sim.core import WarehouseSim
from rtaw_marl.sim.registry import build_sim

__all__ = ["exit_on_user_error", "policies_from_cfg", "sim_from_cfg"]


def exit_on_user_error(fn: Callable[[DictConfig], Any]) -> Callable[[DictConfig], Any]:
    """Turn user errors into one ``error: ...`` line on stderr and exit status 2."""

    @wraps(fn)
    def wrapper(cfg: DictConfig) -> Any:
        try:
            return fn(cfg)
        except (RtawError, OmegaConfBaseException) as exc:
            print(
                f"error: {exc}".splitlines()[0] if isinstance(exc, RtawError) else _omega(exc),
                file=sys.stderr,
            )
            sys.exit(2)

    return wrapper


def _omega(exc: OmegaConfBaseException) -> str:
    key = getattr(exc, "full_key", None)
    first = str(exc).splitlines()[0]
    return f"error: config key {key!r}: {first}" if key else f"error: {first}"


def sim_from_cfg(cfg: DictConfig) -> WarehouseSim:
    """Build the simulator from the ``env``, ``layout``, ``navigator`` and ``tasks`` groups."""
    env = OmegaConf.to_container(cfg.env, resolve=True, throw_on_missing=True)
    layout = OmegaConf.to_container(cfg.layout, resolve=True, throw_on_missing=True)
    tasks = OmegaConf.to_container(cfg.tasks, resolve=True, throw_on_missing=True)
    navigator = OmegaConf.to_container(cfg.navigator, resolve=True, throw_on_missing=True)
    return build_sim(env, layout, navigator, tasks)


def policies_from_cfg(cfg: DictConfig, names: list[str], sim: WarehouseSim) -> dict[str, SimPolicy]:
    """Policies by name: baselines, ``checkpoint`` (one greedy policy per path in
    ``cfg.checkpoint``) and ``rtaw`` (one per shipped policy named in ``cfg.pretrained``)."""
    sources = {"checkpoint": _as_list(cfg.checkpoint), "rtaw": _as_list(cfg.pretrained)}
    for option, key in (("checkpoint", "checkpoint"), ("rtaw", "pretrained")):
        if option in names and not sources[option]:
            raise ConfigError(f"policy={option} needs {key}=... (one value or a list)")
        if sources[option] and option not in names:
            raise ConfigError(f"{key}=... given but policy does not include '{option}'")
    policies: dict[str, SimPolicy] = {}
    for name in names:
        if name not in sources:
            policies[name] = make_baseline(name, navigator=sim.navigator, scale=sim.layout.scale)
            continue
        import torch

        from rtaw_marl.policies.network import load_policy
        from rtaw_marl.policies.pretrained.registry import pretrained_path

        torch.set_num_threads(int(cfg.torch_threads))
        for source in sources[name]:
            if name == "checkpoint":
                policy = load_policy(source)
            else:
                policy = load_policy(pretrained_path(source), name=f"rtaw:{source}")
            policies[policy.name] = policy
    return policies


def _as_list(value: object) -> list[str]:
    if value is None:
        return []
    return [str(value)] if isinstance(value, str) else [str(v) for v in value]
