"""Training: PPO on the batched TorchRL env (:mod:`.ppo`), its collectors, evaluator,
checkpoints, imitation warm start, loggers, and the shipped policies' recipes (:mod:`.zoo`).

Needs the ``train`` extra (torch, tensordict, torchrl); this package itself imports
nothing, so ``import rtaw_marl.training.config`` stays light.
"""
