"""What the command-line entry points share: the Hydra entry, one-line errors, and
building the simulator and the policies from a typed config."""

from __future__ import annotations

import os
import sys
from collections.abc import Callable
from functools import wraps
from typing import Any

import hydra
from hydra.errors import HydraException
from omegaconf import DictConfig
from omegaconf.errors import OmegaConfBaseException

from rtaw_marl.config import CONF_DIR, config_error, register_configs, to_typed
from rtaw_marl.errors import ConfigError, RtawError
from rtaw_marl.evaluation.evaluate import SimPolicy
from rtaw_marl.policies import make_baseline
from rtaw_marl.sim.core import WarehouseSim

__all__ = ["exit_on_user_error", "hydra_entry", "policies_from_cfg", "typed"]


def hydra_entry(config_name: str, task: Callable[[DictConfig], Any]) -> Callable[[], None]:
    """A console entry point: Hydra composes ``config_name`` and calls ``task``.

    A composition error (unknown key, option or value type) becomes one ``error: ...``
    line and exit status 2, like every other user error, instead of Hydra's multi-line
    report and status 1.
    """
    register_configs()
    hydra_main = hydra.main(config_path=str(CONF_DIR), config_name=config_name, version_base="1.3")(
        task
    )

    def main() -> None:
        previous = os.environ.get("HYDRA_FULL_ERROR")
        # Let composition errors reach this frame instead of Hydra's own report.
        os.environ["HYDRA_FULL_ERROR"] = "1"
        try:
            hydra_main()
        except (HydraException, OmegaConfBaseException, RtawError) as exc:
            print(f"error: {config_error(exc)}", file=sys.stderr)
            sys.exit(2)
        finally:
            if previous is None:
                os.environ.pop("HYDRA_FULL_ERROR", None)
            else:
                os.environ["HYDRA_FULL_ERROR"] = previous

    main.__doc__ = f"Console entry point of the {config_name!r} config."
    return main


def exit_on_user_error(fn: Callable[[DictConfig], Any]) -> Callable[[DictConfig], Any]:
    """Turn user errors into one ``error: ...`` line on stderr and exit status 2."""

    @wraps(fn)
    def wrapper(cfg: DictConfig) -> Any:
        try:
            return fn(cfg)
        except (RtawError, HydraException, OmegaConfBaseException) as exc:
            print(f"error: {config_error(exc)}".splitlines()[0], file=sys.stderr)
            sys.exit(2)

    return wrapper


def typed(cfg: DictConfig | Any) -> Any:
    """The typed dataclass of a composed config (a typed config passes through)."""
    return to_typed(cfg) if isinstance(cfg, DictConfig) else cfg


def policies_from_cfg(cfg: Any, names: list[str], sim: WarehouseSim) -> dict[str, SimPolicy]:
    """Policies by name: baselines, ``checkpoint`` (one greedy policy per path in
    ``cfg.checkpoint``) and ``rtaw`` (one per shipped policy named in ``cfg.pretrained``)."""
    sources = {"checkpoint": as_list(cfg.checkpoint), "rtaw": as_list(cfg.pretrained)}
    for option, key in (("checkpoint", "checkpoint"), ("rtaw", "pretrained")):
        if option in names and not sources[option]:
            raise ConfigError(f"policy={option} needs {key}=... (one value or a list)")
        if sources[option] and option not in names:
            raise ConfigError(f"{key}=... given but policy does not include '{option}'")
    policies: dict[str, SimPolicy] = {}
    for name in names:
        if name not in sources:
            policies[name] = make_baseline(
                name, navigator=sim.navigator, scale=sim.layout.scale, params=cfg.baselines
            )
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


def as_list(value: object) -> list[str]:
    """``None`` -> ``[]``, a scalar -> ``[str(value)]``, a list -> its items as strings."""
    if value is None:
        return []
    return [str(value)] if isinstance(value, (str, int)) else [str(v) for v in value]
