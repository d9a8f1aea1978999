"""Environment adapters over the simulator.

* :mod:`rtaw_marl.envs.pettingzoo`: the PettingZoo AEC env (no torch);
* :mod:`rtaw_marl.envs.torchrl`: the batched native TorchRL env used for training;
* :mod:`rtaw_marl.envs.torchrl_wrapper`: TorchRL's ``PettingZooWrapper`` for the AEC env,
  every robot's row filled at once (needs the ``[train]`` extra, as ``torchrl`` does);
* :mod:`rtaw_marl.envs.gymnasium`: the single-agent Gymnasium adapter;
* :mod:`rtaw_marl.envs.spaces`: the Gymnasium spaces of an observation layout;
* :mod:`rtaw_marl.envs.text`: the text rendering of a simulator.

Every adapter observes a decision through :mod:`rtaw_marl.decision` (the one observation
builder, the observation layouts, every agent's view and the global state).

Import the submodule you need: this package imports neither torch nor PettingZoo.
"""
