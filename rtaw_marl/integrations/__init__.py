"""Adapters to other MARL libraries; each module imports its library, this package none.

``rtaw_marl.integrations.benchmarl``: a BenchMARL task (needs ``benchmarl``; docs/benchmarl.md).
"""
