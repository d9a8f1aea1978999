"""Adapters to other MARL libraries; each module imports its library, this package none.

``rtaw_marl.integrations.benchmarl``: a BenchMARL task (needs ``benchmarl``; docs/benchmarl.md).
``benchmarks.sb3``: SB3-contrib's ``MaskablePPO`` with the settings that learn
(needs ``sb3-contrib``; docs/integrations.md).
"""
