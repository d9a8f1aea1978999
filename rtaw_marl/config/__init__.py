"""The typed config spine: Hydra schemas for every option, composition and conversion.

* :mod:`.store` registers each option's dataclass (defined next to the code it
  configures) with Hydra's ConfigStore;
* :func:`compose` composes a primary config (``eval``, ``train``, ``render``) in-process,
  as the command line would;
* :func:`to_typed` turns a composed config into its dataclass, with one-line errors.
"""

from __future__ import annotations

from rtaw_marl.config.convert import (
    CONF_DIR,
    as_plain,
    check_overrides,
    compose,
    config_error,
    to_typed,
)
from rtaw_marl.config.store import GROUPS, register_configs

__all__ = [
    "CONF_DIR",
    "GROUPS",
    "as_plain",
    "check_overrides",
    "compose",
    "config_error",
    "register_configs",
    "to_typed",
]
