"""Composing configs in-process and converting them to typed dataclasses."""

from __future__ import annotations

import dataclasses
import re
from collections.abc import Sequence
from typing import Any

from hydra import compose as hydra_compose
from hydra import initialize_config_dir
from hydra.core.override_parser.overrides_parser import OverridesParser
from hydra.errors import HydraException, MissingConfigException
from omegaconf import BooleanNode, DictConfig, OmegaConf
from omegaconf.errors import OmegaConfBaseException

from rtaw_marl.config.help import register_help
from rtaw_marl.config.store import APPS, CONF_DIR, register_configs
from rtaw_marl.errors import ConfigError, RtawError, did_you_mean
from rtaw_marl.sim.builder import SimGroups
from rtaw_marl.training.config import RENAMED as TRAIN_RENAMED
from rtaw_marl.utils.plain import as_plain
from rtaw_marl.utils.renamed import RENAMED, renamed_key

__all__ = [
    "CONF_DIR",
    "as_plain",
    "check_overrides",
    "check_renamed",
    "compose",
    "config_error",
    "to_typed",
]


def compose(
    config_name: str,
    overrides: list[str] | tuple[str, ...] = (),
    return_hydra_config: bool = False,
) -> DictConfig:
    """Compose ``config_name`` with command-line style ``overrides``, as the CLI does
    (with ``return_hydra_config``, the ``hydra`` node too: launcher, sweeper).

    Raises:
        ConfigError: Composition failed (unknown key, option or value type); one line.
    """
    register_configs()
    register_help()
    check_renamed(config_name, overrides)
    try:
        with initialize_config_dir(config_dir=str(CONF_DIR), version_base="1.3"):
            cfg = hydra_compose(
                config_name=config_name,
                overrides=list(overrides),
                return_hydra_config=return_hydra_config,
            )
    except (HydraException, OmegaConfBaseException) as exc:
        raise config_error(exc) from exc
    check_overrides(cfg, overrides)
    return cfg


def check_overrides(cfg: DictConfig, overrides: Sequence[str]) -> None:
    """Refuse a boolean key given anything but ``true`` or ``false``.

    OmegaConf reads ``yes``/``no``/``on``/``off``/``1``/``0`` into a ``bool`` field, so
    ``lower_bound=off`` or ``progress=2`` would silently pick a side; once composed the
    word is gone, so the overrides themselves are checked (Hydra parses ``true`` and
    ``false``, in any case, as real booleans).

    Args:
        cfg: The composed config.
        overrides: The command-line overrides it was composed with.

    Raises:
        ConfigError: A boolean key was given another value; the message names it.
    """
    for text in overrides:
        key = _override_key(text)
        # Only a boolean key's override is parsed: parsing is quadratic in a list's length
        # (ANTLR's child lookup), and Hydra hands over seeds='${range:0,100000}' expanded.
        if key is None or key.startswith("hydra.") or not _is_boolean(cfg, key):
            continue
        try:
            (override,) = OverridesParser.create().parse_overrides([text])
        except HydraException:
            continue  # Hydra has already accepted it; nothing to add
        if override.is_delete() or override.is_sweep_override():
            continue
        value = override.value()
        if value is None or isinstance(value, bool):
            continue
        if isinstance(value, str) and "${" in value:
            continue  # an interpolation: its result is typed when it resolves
        raise ConfigError(f"{key} must be true or false, got {value!r}")


def check_renamed(config_name: str, overrides: Sequence[str]) -> None:
    """Refuse a key that was renamed, naming its new name: ``env.num_robots=50`` is
    ``sim.num_robots`` now in every command with the simulator's keys
    (:data:`rtaw_marl.utils.renamed.RENAMED`), ``rtaw-train eval.every_frames=1024``
    ``selection.every_frames`` (:data:`rtaw_marl.training.config.RENAMED`). Checked
    before composing, whose own error would only say the key is unknown.

    Raises:
        ConfigError: An override sets (or adds, or deletes) a renamed key, or chooses
            an option of a renamed group (``env=default``).
    """
    if config_name == "train":
        table = TRAIN_RENAMED
    elif isinstance(APPS.get(config_name), type) and issubclass(APPS[config_name], SimGroups):
        table = RENAMED
    else:
        return
    for text in overrides:
        if text.startswith("-") or ("=" not in text and not text.startswith("~")):
            continue
        key = text.partition("=")[0].lstrip("~+").partition("@")[0].strip()
        message = renamed_key(key, table)
        if message is not None:
            raise ConfigError(message)


def _override_key(text: str) -> str | None:
    """The config key an override sets (``+a.b@pkg=1`` -> ``a.b``); ``None`` for a
    deletion or anything without ``=``."""
    head, sep, _ = text.partition("=")
    if not sep or head.startswith("~"):
        return None
    return head.lstrip("+").partition("@")[0].strip() or None


def _is_boolean(cfg: DictConfig, key: str) -> bool:
    """Whether ``key`` names a boolean field of ``cfg`` (a group choice, a list item or
    an unknown key is not one)."""
    parent_key, _, leaf = key.rpartition(".")
    try:
        parent = OmegaConf.select(cfg, parent_key) if parent_key else cfg
    except OmegaConfBaseException:
        return False
    return (
        isinstance(parent, DictConfig)
        and leaf in parent
        and isinstance(parent._get_node(leaf), BooleanNode)
    )


def to_typed(cfg: DictConfig) -> Any:
    """The dataclass behind a composed config (``TrainConfig``, ``EvalConfig``, ...).

    Every group becomes its option's dataclass, whose ``__post_init__`` checks values.

    Raises:
        ConfigError: A mandatory value is missing or a value is invalid; one line.
    """
    _check_keys(cfg, "")
    try:
        return OmegaConf.to_object(cfg)
    except (OmegaConfBaseException, TypeError) as exc:
        raise config_error(exc) from exc


def _check_keys(node: DictConfig, prefix: str) -> None:
    """Refuse keys a schema does not declare.

    Hydra's ``+key=value`` appends even to a typed node, and ``to_object`` would then drop
    the key silently; a typo must be an error instead.
    """
    schema = OmegaConf.get_type(node)
    if dataclasses.is_dataclass(schema):
        valid = [f.name for f in dataclasses.fields(schema)]
        for key in node:
            if key not in valid:
                raise _unknown_key(f"{prefix}{key}", schema)  # type: ignore[arg-type]
    for key in node:
        child = node._get_node(key)
        if isinstance(child, DictConfig) and not child._is_missing() and not child._is_none():
            _check_keys(child, f"{prefix}{key}.")


def config_error(exc: BaseException) -> RtawError:
    """One-line :class:`ConfigError` for a Hydra/OmegaConf error, naming the key.

    OmegaConf's messages span several lines (``full_key: ...``, ``object_type=...``);
    the user needs the key, what is wrong, and for an unknown key the valid ones.
    """
    if isinstance(exc, RtawError):
        return exc
    if "LexerNoViableAltException" in str(exc):
        return _unparsable(str(exc))
    if isinstance(exc, MissingConfigException) and exc.options is not None:
        return _missing_option(exc, [o for o in exc.options if not o.startswith("_")])
    cause = exc
    while not isinstance(cause, OmegaConfBaseException) and cause.__cause__ is not None:
        cause = cause.__cause__
    lines = [line.strip() for line in str(cause).splitlines() if line.strip()]
    first = lines[0] if lines else type(cause).__name__
    if first.endswith(":") and len(lines) > 1:
        # Hydra's "X raised while composing config:" puts the reason on the next line.
        first = f"{first} {lines[1]}"
    key = getattr(cause, "full_key", None)
    if isinstance(cause, OmegaConfBaseException) and key:
        object_type = getattr(cause, "object_type", None)
        if "not in" in first and dataclasses.is_dataclass(object_type):
            return _unknown_key(key, object_type)  # type: ignore[arg-type]
        return ConfigError(f"config key {key!r}: {first}")
    return ConfigError(first)


def _unknown_key(key: str, schema: type) -> ConfigError:
    """``unknown config key 'sim.num_robot'; valid keys there: ...; did you mean
    'sim.num_robots'?`` for a ``key`` that ``schema`` (its parent's) does not declare."""
    group, _, leaf = key.rpartition(".")
    parent = f"{group}." if group else ""
    keys = [f.name for f in dataclasses.fields(schema) if f.name != "name"]  # type: ignore[arg-type]
    hint = did_you_mean(leaf, keys, prefix=parent)
    return ConfigError(f"unknown config key {key!r}; {_settable(schema, group)}{hint}")


def _missing_option(exc: MissingConfigException, options: list[str]) -> ConfigError:
    """Hydra's ``Could not find 'navigator/sipq'`` with the group's options and the
    closest ones (``did you mean 'navigator=sipp'?``)."""
    first = str(exc).strip().splitlines()[0]
    # Hydra begins with the config that chose the group ("In 'eval': ", or "In
    # 'setting/default': " for a simulator group, config.store.SETTINGS): not what the
    # user typed, so left out.
    first = re.sub(r"^In '[^']*': ", "", first)
    group, _, name = (exc.missing_cfg_file or "").rpartition("/")
    # The group as typed on the command line: hydra/launcher=..., navigator=...
    hint = did_you_mean(name, options, prefix=f"{group}=") if group else ""
    return ConfigError(f"{first}; available: {', '.join(options)}{hint}")


def _unparsable(text: str) -> ConfigError:
    """The line for an override Hydra's grammar cannot read (``LexerNoViableAltException:
    <override>`` then a caret line): unquoted values are ASCII words and paths only, so
    a non-ASCII value gets the quoted form to type instead."""
    override = text.partition(":")[2].strip().splitlines()[0].strip()
    key, sep, value = override.partition("=")
    if override.isascii() or not sep:
        return ConfigError(f"cannot parse the override {override!r}")
    return ConfigError(
        f"cannot parse the override {override!r}: a value with non-ASCII characters must "
        f"be quoted, e.g. '{key}=\"{value}\"'"
    )


def _settable(schema: type, group: str) -> str:
    """The keys a user can set on ``schema`` (at ``group``), for an unknown-key message.

    An option's ``name`` is fixed by the option (``navigator=cbs`` chooses it), so it is
    not offered; an option with nothing else to set says so.
    """
    keys = [f.name for f in dataclasses.fields(schema) if f.name != "name"]  # type: ignore[arg-type]
    if keys:
        return f"valid keys there: {', '.join(keys)}"
    name = getattr(schema, "__dataclass_fields__", {}).get("name")
    option = f"{group}={name.default}" if group and name is not None else group or "this config"
    return f"{option} takes no keys"
