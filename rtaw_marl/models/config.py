"""The network options (the ``model`` config group); plain Python, no torch."""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["MODELS", "RTAWConfig"]


@dataclass(kw_only=True)
class RTAWConfig:
    """The paper's attention-inspired network (:mod:`rtaw_marl.models.rtaw`).

    Attributes:
        name: The option's name.
        embed_dim: Embedding size of robots and tasks (paper: 16).
        head_dim: Hidden size of the per-task scoring layer (paper: 8).
        critic_hidden: Hidden size of the critic's value head (our design).
    """

    name: str = "rtaw"
    embed_dim: int = 16
    head_dim: int = 8
    critic_hidden: int = 32

    def __post_init__(self) -> None:
        from rtaw_marl.errors import ConfigError

        if self.name != "rtaw":
            raise ConfigError(f"model.name must be 'rtaw' for these keys, got {self.name!r}")
        for key in ("embed_dim", "head_dim", "critic_hidden"):
            value = getattr(self, key)
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise ConfigError(f"model.{key} must be an integer >= 1, got {value!r}")


MODELS: dict[str, type[RTAWConfig]] = {"rtaw": RTAWConfig}
