"""rtaw_marl: learned lifelong multi-robot task allocation in warehouses (RTAW).

``from rtaw_marl import warehouse_v1`` gives the PettingZoo environment. Importing the
package loads neither torch nor PettingZoo; the env registers itself with PettingZoo as
``rtaw/warehouse-v1`` when :mod:`rtaw_marl.envs.pettingzoo` is imported (``from
rtaw_marl import warehouse_v1`` does that), and at once if PettingZoo is already loaded,
so ``import pettingzoo, rtaw_marl; pettingzoo.make("aec", "rtaw/warehouse-v1")`` works.
PettingZoo has that registry from 1.27 on; with an earlier PettingZoo (>= 1.25, e.g. beside
AgileRL) the env works the same and registration is skipped.

The single-agent Gymnasium adapter (:mod:`rtaw_marl.envs.gymnasium`) registers the same
way with Gymnasium, as ``rtaw/warehouse-single-v1``: ``import gymnasium, rtaw_marl;
gymnasium.make("rtaw/warehouse-single-v1")`` works (its old id ``rtaw/Warehouse-v1`` still
makes it, with a ``DeprecationWarning``).
"""

from __future__ import annotations

import sys

__all__ = ["ENV_ID", "GYMNASIUM_ENV_ID", "__version__", "register_envs"]
__version__ = "0.1.0"
#: The env family: module ``warehouse_v1`` (metadata name ``warehouse_v1``), PettingZoo
#: id ``rtaw/warehouse-v1``, and the single-agent Gymnasium adapter of the same env.
ENV_ID = "rtaw/warehouse-v1"
GYMNASIUM_ENV_ID = "rtaw/warehouse-single-v1"
#: The Gymnasium adapter's id before it joined the family; still made, with a warning.
_OLD_GYMNASIUM_ID = "rtaw/Warehouse-v1"


def register_envs() -> None:
    """Register ``rtaw/warehouse-v1`` in PettingZoo's AEC registry (a no-op before
    PettingZoo 1.27, which has no registry) and ``rtaw/warehouse-single-v1`` in Gymnasium's
    (idempotent)."""
    _register_pettingzoo()
    _register_gymnasium()


def _register_pettingzoo() -> None:
    try:
        from pettingzoo.env_registry.registration import aec_registry, register
    except ImportError:
        return

    if ENV_ID not in aec_registry:
        register("aec", ENV_ID, entry_point="rtaw_marl.envs.pettingzoo:env")


def _register_gymnasium() -> None:
    import gymnasium

    if GYMNASIUM_ENV_ID not in gymnasium.registry:
        gymnasium.register(GYMNASIUM_ENV_ID, entry_point="rtaw_marl.envs.gymnasium:WarehouseEnv")
    if _OLD_GYMNASIUM_ID not in gymnasium.registry:
        gymnasium.register(_OLD_GYMNASIUM_ID, entry_point="rtaw_marl.envs.gymnasium:deprecated_env")


if "pettingzoo" in sys.modules:
    _register_pettingzoo()
if "gymnasium" in sys.modules:
    _register_gymnasium()
