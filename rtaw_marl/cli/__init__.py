"""Command-line entry points: thin Hydra mains over typed configs (:mod:`rtaw_marl.config`)."""
