"""Composing configs in-process and converting them to typed dataclasses."""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

from hydra import compose as hydra_compose
from hydra import initialize_config_dir
from hydra.errors import HydraException, MissingConfigException
from omegaconf import DictConfig, OmegaConf
from omegaconf.errors import OmegaConfBaseException

from rtaw_marl.config.store import register_configs
from rtaw_marl.errors import ConfigError, RtawError
from rtaw_marl.utils.plain import as_plain

__all__ = ["CONF_DIR", "as_plain", "compose", "config_error", "to_typed"]

#: The packaged Hydra config folder (``rtaw_marl/conf``).
CONF_DIR = Path(__file__).resolve().parents[1] / "conf"


def compose(
    config_name: str,
    overrides: list[str] | tuple[str, ...] = (),
    return_hydra_config: bool = False,
) -> DictConfig:
    """Compose ``config_name`` with command-line style ``overrides``, as the CLI does
    (with ``return_hydra_config``, the ``hydra`` node too: launcher, sweeper).

    Raises:
        ConfigError: Composition failed (unknown key, option or value type); one line.
    """
    register_configs()
    try:
        with initialize_config_dir(config_dir=str(CONF_DIR), version_base="1.3"):
            return hydra_compose(
                config_name=config_name,
                overrides=list(overrides),
                return_hydra_config=return_hydra_config,
            )
    except (HydraException, OmegaConfBaseException) as exc:
        raise config_error(exc) from exc


def to_typed(cfg: DictConfig) -> Any:
    """The dataclass behind a composed config (``TrainConfig``, ``EvalConfig``, ...).

    Every group becomes its option's dataclass, whose ``__post_init__`` checks values.

    Raises:
        ConfigError: A mandatory value is missing or a value is invalid; one line.
    """
    _check_keys(cfg, "")
    try:
        return OmegaConf.to_object(cfg)
    except (OmegaConfBaseException, TypeError) as exc:
        raise config_error(exc) from exc


def _check_keys(node: DictConfig, prefix: str) -> None:
    """Refuse keys a schema does not declare.

    Hydra's ``+key=value`` appends even to a typed node, and ``to_object`` would then drop
    the key silently; a typo must be an error instead.
    """
    schema = OmegaConf.get_type(node)
    if dataclasses.is_dataclass(schema):
        valid = [f.name for f in dataclasses.fields(schema)]
        for key in node:
            if key not in valid:
                raise ConfigError(
                    f"unknown config key '{prefix}{key}'; valid keys there: {', '.join(valid)}"
                )
    for key in node:
        child = node._get_node(key)
        if isinstance(child, DictConfig) and not child._is_missing() and not child._is_none():
            _check_keys(child, f"{prefix}{key}.")


def config_error(exc: BaseException) -> RtawError:
    """One-line :class:`ConfigError` for a Hydra/OmegaConf error, naming the key.

    OmegaConf's messages span several lines (``full_key: ...``, ``object_type=...``);
    the user needs the key, what is wrong, and for an unknown key the valid ones.
    """
    if isinstance(exc, RtawError):
        return exc
    if isinstance(exc, MissingConfigException) and exc.options is not None:
        first = str(exc).strip().splitlines()[0]
        options = ", ".join(o for o in exc.options if not o.startswith("_"))
        return ConfigError(f"{first}; available: {options}")
    cause = exc
    while not isinstance(cause, OmegaConfBaseException) and cause.__cause__ is not None:
        cause = cause.__cause__
    lines = [line.strip() for line in str(cause).splitlines() if line.strip()]
    first = lines[0] if lines else type(cause).__name__
    if first.endswith(":") and len(lines) > 1:
        # Hydra's "X raised while composing config:" puts the reason on the next line.
        first = f"{first} {lines[1]}"
    key = getattr(cause, "full_key", None)
    if isinstance(cause, OmegaConfBaseException) and key:
        valid = _valid_keys(cause)
        if "not in" in first and valid:
            return ConfigError(f"unknown config key {key!r}; valid keys there: {valid}")
        return ConfigError(f"config key {key!r}: {first}")
    return ConfigError(first)


def _valid_keys(exc: OmegaConfBaseException) -> str:
    object_type = getattr(exc, "object_type", None)
    if object_type is not None and dataclasses.is_dataclass(object_type):
        return ", ".join(f.name for f in dataclasses.fields(object_type))
    return ""
