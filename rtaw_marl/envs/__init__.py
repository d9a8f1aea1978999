"""Environment adapters over the simulator.

* :mod:`rtaw_marl.envs.pettingzoo`: the PettingZoo AEC env (no torch);
* :mod:`rtaw_marl.envs.torchrl`: the batched native TorchRL env used for training;
* :mod:`rtaw_marl.envs.torchrl_wrapper`: TorchRL's ``PettingZooWrapper`` for the AEC env,
  every robot's row filled at once (needs the ``[train]`` extra, as ``torchrl`` does);
* :mod:`rtaw_marl.envs.observations`: the PettingZoo env's observation layouts, every
  agent's view and the global state;
* :mod:`rtaw_marl.envs.features`: the observation features both share;
* :mod:`rtaw_marl.envs.text`: the text rendering of a simulator.

Import the submodule you need: this package imports neither torch nor PettingZoo.
"""
