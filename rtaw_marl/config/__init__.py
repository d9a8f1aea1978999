"""The typed config spine: Hydra schemas for every option, composition and conversion.

* :mod:`.store` registers each option's dataclass (defined next to the code it
  configures) with Hydra's ConfigStore, and the options made from registries
  (``scenario=``, ``row=``: :mod:`.scenarios`; ``+zoo=``);
* :func:`compose` composes a primary config (``eval``, ``train``, ``render``) in-process,
  as the command line would;
* :func:`to_typed` turns a composed config into its dataclass, with one-line errors.
"""

from __future__ import annotations

from rtaw_marl.errors import missing_extra

# Hydra and OmegaConf come with the command-line extra: without it, one error that names
# it (errors.missing_extra), no traceback of a bare ModuleNotFoundError.
try:
    from rtaw_marl.config.convert import (
        CONF_DIR,
        as_plain,
        check_overrides,
        check_renamed,
        compose,
        config_error,
        to_typed,
    )
    from rtaw_marl.config.store import GROUPS, group_options, register_configs
except ModuleNotFoundError as exc:
    raise missing_extra(exc, __name__, "cli") from None

__all__ = [
    "CONF_DIR",
    "GROUPS",
    "as_plain",
    "check_overrides",
    "check_renamed",
    "compose",
    "config_error",
    "group_options",
    "register_configs",
    "to_typed",
]
