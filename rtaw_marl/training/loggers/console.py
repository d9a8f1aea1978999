"""torchrl's console notes hidden during a run (its warnings and errors still show)."""

from __future__ import annotations

import logging
import os

__all__ = ["quiet_torchrl_logs"]


def quiet_torchrl_logs() -> None:
    """Hide torchrl's INFO console lines; its warnings and errors still show.

    torchrl logs notes such as ``Initialized LazyTensorStorage with ... shape`` at INFO,
    in colour, on stdout; a user can do nothing about them. A level set through
    ``RL_LOGGING_LEVEL`` (torchrl's own switch, read at its import) is left as it is.
    """
    if "RL_LOGGING_LEVEL" in os.environ:
        return
    import torchrl  # noqa: F401  (its import sets the level to INFO: lower it after that)

    logger = logging.getLogger("torchrl")
    if logger.getEffectiveLevel() < logging.WARNING:
        logger.setLevel(logging.WARNING)
