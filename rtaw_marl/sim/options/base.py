"""What every option shares: its fixed registry ``name``, and building options by name."""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, ClassVar

from rtaw_marl.errors import ConfigError, did_you_mean, unknown_name
from rtaw_marl.utils.checks import check_fields

__all__ = ["Option", "option_from"]


@dataclass(kw_only=True)
class Option:
    """Shared by every option.

    Attributes:
        name: The option's registry name (fixed by the option; choose an option with
            ``group=NAME``).
    """

    name: str

    def __post_init__(self) -> None:
        expected = type(self).__dataclass_fields__["name"].default
        if self.name != expected:
            raise ConfigError(
                f"{self.group}.name is {self.name!r} but the keys are those of {expected!r}; "
                f"choose another option with {self.group}=NAME instead"
            )
        check_fields(self, f"{self.group}.")

    group: ClassVar[str] = ""


def option_from(
    registry: Mapping[str, type[Option]], group: str, spec: str | Mapping[str, Any] | Option
) -> Option:
    """An option of ``registry`` from a name, a ``{"name": ..., **keys}`` mapping or itself.

    Raises:
        ConfigError: The name or a key is unknown (the message lists the valid ones), or a
            required key is missing.
    """
    if isinstance(spec, Option):
        return spec
    params = {"name": spec} if isinstance(spec, str) else dict(spec)
    name = params.get("name")
    if name is None:
        raise ConfigError(f"{group} config needs a 'name'; available: {', '.join(registry)}")
    if name not in registry:
        raise unknown_name(group, str(name), list(registry))
    cls = registry[name]
    keys = [f.name for f in dataclasses.fields(cls)]
    unknown = sorted(set(params) - set(keys))
    if unknown:
        settable = [k for k in keys if k != "name"]
        raise ConfigError(
            f"unknown key {group}.{unknown[0]} for {group}={name}; valid keys: "
            f"{', '.join(settable) or 'none'}{did_you_mean(unknown[0], settable, f'{group}.')}"
        )
    required = [
        f.name
        for f in dataclasses.fields(cls)
        if f.default is dataclasses.MISSING
        and f.default_factory is dataclasses.MISSING
        and params.get(f.name) is None
    ]
    if required:
        raise ConfigError(f"{group}={name} needs {group}.{required[0]}=...")
    return cls(**params)
