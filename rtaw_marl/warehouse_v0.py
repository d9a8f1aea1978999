"""``warehouse_v0`` is gone: v1 changed the observation layout (see its Version History).

As PettingZoo does for a superseded version, ``env()`` and ``raw_env()`` raise
``pettingzoo.utils.deprecated_module.DeprecatedEnv`` naming the version to use.
"""

from __future__ import annotations

from typing import Any, NoReturn

from pettingzoo.utils.deprecated_module import DeprecatedEnv

__all__ = ["env", "raw_env"]


def env(*args: Any, **kwargs: Any) -> NoReturn:
    """Raise ``DeprecatedEnv``: use :mod:`rtaw_marl.warehouse_v1`."""
    raise DeprecatedEnv(
        "warehouse_v0 is now deprecated, use warehouse_v1 instead (from rtaw_marl import "
        "warehouse_v1; observations are now {'observation': ..., 'action_mask': ...} and "
        "the episode metrics are flat keys of infos)"
    )


raw_env = env
