"""Helpers shared by the command-line entry points."""

from __future__ import annotations

import sys
from collections.abc import Callable
from functools import wraps
from typing import Any

from omegaconf import DictConfig, OmegaConf
from omegaconf.errors import OmegaConfBaseException

from rtaw_marl.errors import RtawError
from rtaw_marl.sim.core import WarehouseSim
from rtaw_marl.sim.registry import build_sim

__all__ = ["exit_on_user_error", "sim_from_cfg"]


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
    return build_sim(env, layout, str(cfg.navigator.name), tasks)
