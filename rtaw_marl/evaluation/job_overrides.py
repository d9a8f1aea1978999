"""What a Hydra job's ``.hydra/overrides.yaml`` says about its setting.

``rtaw-results`` names each setting of a sweep by the overrides that differ between its
jobs: :func:`job_overrides` reads one job's file, checked, under today's key names.
"""

from __future__ import annotations

from pathlib import Path

from rtaw_marl.errors import ConfigError
from rtaw_marl.evaluation.journal import NOT_SETTING
from rtaw_marl.utils.renamed import upgrade_command

__all__ = ["job_overrides"]


def job_overrides(path: Path) -> dict[str, str] | None:
    """The job's overrides (``.hydra/overrides.yaml``) by key, without the options
    that are no setting; ``None`` when the file is not there. Overrides written before
    the simulator's keys were renamed (``env.num_robots=10``) are read under today's
    names (``sim.num_robots``), as the results file's config is.

    Raises:
        ConfigError: The file cannot be read, or is not what Hydra writes there (a list
            of ``KEY=VALUE`` strings); the message names it.
    """
    file = path.parent / ".hydra" / "overrides.yaml"
    if not file.is_file():
        return None
    out: dict[str, str] = {}
    for item in upgrade_command(_items(file)):
        key, _, value = item.partition("=")
        key = key.lstrip("+~")
        if key.split(".")[0].split("/")[0] not in (*NOT_SETTING, "hydra"):
            out[key] = value
    return out


def _items(file: Path) -> list[str]:
    """The strings of an overrides file, checked: Hydra writes a list of them."""
    import yaml  # omegaconf's dependency: the cli extra

    try:
        items = yaml.safe_load(file.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, yaml.YAMLError) as exc:
        raise ConfigError(f"{file}: cannot be read ({_first_line(exc)})") from None
    except RecursionError:  # PyYAML composes nested nodes recursively
        raise ConfigError(f"{file}: nested too deeply to be a Hydra overrides list") from None
    if items is None:  # an empty file: a job run without overrides
        return []
    if not isinstance(items, list) or not all(isinstance(item, str) for item in items):
        raise ConfigError(
            f"{file}: not a Hydra overrides list (a list of KEY=VALUE strings, as "
            "Hydra writes for each job)"
        )
    return items


def _first_line(exc: BaseException) -> str:
    return (str(exc).strip().splitlines() or [type(exc).__name__])[0]
