"""Networks (:mod:`.rtaw`), their TorchRL actor/critic modules (:mod:`.actor_critic`),
their typed options (:mod:`.config`, no torch) and checkpoint I/O (:mod:`.checkpoint`).

Import the submodule you need: this package does not import torch by itself.
"""
