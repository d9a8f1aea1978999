"""rtaw_marl: learned lifelong multi-robot task allocation in warehouses (RTAW).

``from rtaw_marl import warehouse_v0`` gives the PettingZoo environment; importing the
package also registers it as ``rtaw/warehouse-v0`` in PettingZoo's registry, so
``pettingzoo.make("aec", "rtaw/warehouse-v0")`` works after ``import rtaw_marl``.
"""

from __future__ import annotations

from pettingzoo.env_registry.registration import aec_registry, register

from rtaw_marl import warehouse_v0

__all__ = ["ENV_ID", "__version__", "warehouse_v0"]
__version__ = "0.1.0"
ENV_ID = "rtaw/warehouse-v0"

if ENV_ID not in aec_registry:
    register("aec", ENV_ID, entry_point="rtaw_marl.env.warehouse:env")
