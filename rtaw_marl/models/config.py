"""The network options (the ``model`` config group); plain Python, no torch."""

from __future__ import annotations

from dataclasses import dataclass

from rtaw_marl.utils.checks import check_fields

__all__ = ["MODELS", "RIVAL_DIM", "ModelConfig", "RTAWConfig", "RTAWPlusConfig"]

#: Width of RTAW+'s rival keys and values (fixed: the rival tokens dominate its cost).
RIVAL_DIM = 16


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
        _check_sizes(self, ("embed_dim", "head_dim", "critic_hidden"))


@dataclass(kw_only=True)
class RTAWPlusConfig:
    """RTAW+, the relational attention network (:mod:`rtaw_marl.models.rtaw_plus`).

    Attributes:
        name: The option's name.
        embed_dim: Token size ``E`` of tasks and rivals.
        heads: Attention heads (must divide ``embed_dim``).
        critic_hidden: Hidden size of the critic's value head.
        critic_fleet: The critic (used only in training) also sees the whole fleet: the
            robots' features, embedded and mean-pooled. ``False`` keeps the critic to
            the acting robot's relational view, as the actor (an ablation).
        fleet_summary: With ``critic_fleet``, the critic reads the fleet as a fixed-size
            summary (``fleet [8]``: quantiles and mean of the robots' times until
            free, :func:`~rtaw_marl.decision.features.fleet_features`) instead of every
            robot's row (``robots [M, 3]``): neither the update's cost nor a batch's
            size then grows with ``M``, and simulators with different fleets can share
            a batch (``mix``). ``False`` is the shipped per-row policies' critic.
    """

    name: str = "rtaw_plus"
    embed_dim: int = 32
    heads: int = 4
    critic_hidden: int = 64
    critic_fleet: bool = True
    fleet_summary: bool = False

    def __post_init__(self) -> None:
        from rtaw_marl.errors import ConfigError

        if self.name != "rtaw_plus":
            raise ConfigError(f"model.name must be 'rtaw_plus' for these keys, got {self.name!r}")
        _check_sizes(self, ("embed_dim", "heads", "critic_hidden"))
        for key in ("critic_fleet", "fleet_summary"):
            if not isinstance(getattr(self, key), bool):
                raise ConfigError(f"model.{key} must be true or false, got {getattr(self, key)!r}")
        if self.fleet_summary and not self.critic_fleet:
            raise ConfigError(
                "model.fleet_summary=true summarises the fleet the critic sees, but "
                "model.critic_fleet=false shows it none: set one of them"
            )
        for width in (self.embed_dim, RIVAL_DIM):
            if width % self.heads:
                raise ConfigError(
                    f"model.heads={self.heads} must divide model.embed_dim={self.embed_dim} "
                    f"and the rival width {RIVAL_DIM} (a multiple of it is needed)"
                )


def _check_sizes(config: object, keys: tuple[str, ...]) -> None:
    from rtaw_marl.errors import ConfigError

    check_fields(config, "model.")
    for key in keys:
        value = getattr(config, key)
        if isinstance(value, bool) or not isinstance(value, int) or value < 1:
            raise ConfigError(f"model.{key} must be an integer >= 1, got {value!r}")


ModelConfig = RTAWConfig | RTAWPlusConfig

MODELS: dict[str, type[RTAWConfig] | type[RTAWPlusConfig]] = {
    "rtaw": RTAWConfig,
    "rtaw_plus": RTAWPlusConfig,
}
