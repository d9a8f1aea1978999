"""``--help`` of the Hydra commands: only the command's own config groups and keys.

Hydra's default help lists every group of the config search path, so ``rtaw-eval
--help`` offered ``algo`` and ``collector`` (training groups it refuses) and the
internal ``schema/*`` groups. Each command's YAML instead sets::

    hydra:
      help:
        app_name: rtaw-eval
        header: "rtaw-eval: ..."
        footer: "Examples: ..."
        template: ${rtaw_help:eval}

and the ``rtaw_help`` resolver (:func:`register_help`) writes the page from the composed
config: the groups the command's defaults list names (:func:`app_groups`) with their
options, the current choice starred, then every key with its current value (the command
line's overrides included) and the first sentence of its ``Attributes:`` entry, the
same text docs/configuration.md is generated from.
"""

from __future__ import annotations

import dataclasses
import re
import shutil
import textwrap
from typing import Any

import yaml
from hydra.core.global_hydra import GlobalHydra
from omegaconf import DictConfig, ListConfig, OmegaConf

from rtaw_marl.config.reference import attribute_docs
from rtaw_marl.config.store import CONF_DIR, group_options
from rtaw_marl.sim.builder import DEFAULT_OPTIONS

__all__ = ["APPENDABLE", "GROUP_DOCS", "app_groups", "help_text", "register_help"]

#: Groups a command takes only with ``+`` (not in its defaults list): train's zoo recipes.
APPENDABLE: dict[str, tuple[str, ...]] = {"train": ("zoo",)}

#: One line per config group, shown beside its options.
GROUP_DOCS: dict[str, str] = {
    "sim": "the simulator: fleet, queue, episode and noise",
    "layout": "the warehouse map",
    "navigator": "distances, and how robots travel (instant or collision-free)",
    "tasks": "the task stream",
    "scenario": "a named setting: layout, navigator, tasks and fleet at once",
    "row": "a row of the paper's tables: its scenario and shipped policies",
    "experiment": "a whole experiment: fixed values and a sweep (-m)",
    "recipe": "a preset of training keys for a purpose (new_map: a map of your own)",
    "model": "the policy network",
    "algo": "PPO's hyperparameters",
    "collector": "where episodes are collected: local processes or Ray",
    "logger": "where training metrics go",
    "zoo": "a shipped policy's training recipe (+zoo=NAME)",
}

#: Where a key's meaning starts, and how much of a long value to show.
_KEY_COLUMN, _VALUE_CHARS = 36, 28

_SENTENCE_END = re.compile(r"(?<=[a-z0-9)`'\]])\.(\s|$)")


def app_groups(app: str) -> list[str]:
    """The config groups ``app`` takes: those its defaults list names
    (``rtaw_marl/conf/<app>.yaml``), then its :data:`APPENDABLE` ones."""
    primary = yaml.safe_load((CONF_DIR / f"{app}.yaml").read_text()) or {}
    groups = []
    for entry in primary.get("defaults", []):
        if isinstance(entry, str) and entry.startswith("/setting/"):
            # "- /setting/default@_here_": the simulator groups (config.store.SETTINGS).
            groups += [g for g in DEFAULT_OPTIONS if g not in groups]
        # "- model: rtaw" names a group; "- /schema/eval@_here_" and "- _self_" do not.
        if isinstance(entry, dict) and len(entry) == 1:
            (key,) = entry
            group = str(key).partition("@")[0]
            if not group.startswith(("/", "override ")):
                groups.append(group)
    return groups + [g for g in APPENDABLE.get(app, ()) if g not in groups]


def register_help() -> None:
    """Register the ``rtaw_help`` resolver the commands' ``hydra.help.template`` names
    (once per process)."""
    if not OmegaConf.has_resolver("rtaw_help"):
        OmegaConf.register_new_resolver("rtaw_help", _help_template)


def _help_template(app: str, *, _root_: DictConfig) -> str:
    """:func:`help_text` as a Hydra help template: its ``$`` doubled, since Hydra
    substitutes ``$NAME`` placeholders in the template."""
    return help_text(app, _root_).replace("$", "$$")


def help_text(app: str, cfg: DictConfig) -> str:
    """The help page of ``app`` for its composed config ``cfg`` (``hydra`` node included).

    Args:
        app: The primary config's name (``eval``, ``train``, ...).
        cfg: The config composed with the command line's overrides.
    """
    meta = OmegaConf.select(cfg, "hydra.help", default=None)
    name = str(meta.app_name) if meta is not None else f"rtaw-{app}"
    parts = [
        str(meta.header).rstrip() if meta is not None else name,
        "",
        f"Usage: {name} [-m] [GROUP=OPTION ...] [KEY=VALUE ...]",
    ]
    groups = app_groups(app)
    if groups:
        choices = OmegaConf.select(cfg, "hydra.runtime.choices", default=None) or {}
        parts += ["", "== Config groups (GROUP=OPTION; * the current choice) ==", ""]
        parts += [_group_line(g, choices.get(g)) for g in groups]
    parts += ["", "== Keys (KEY=current value: what it sets) ==", ""]
    parts += _key_lines(cfg, "")
    if meta is not None and str(meta.footer).strip():
        parts += ["", str(meta.footer).rstrip()]
    parts += [
        "",
        "Every key in full: docs/configuration.md. Hydra's own flags (--multirun, --cfg job, ...):",
        f'{name} --hydra-help. Shell completion: eval "$({name} -sc install=bash)".',
    ]
    return "\n".join(parts) + "\n"


def _width() -> int:
    """The terminal's width (100 columns when not a terminal), at least 80."""
    return max(shutil.get_terminal_size((100, 24)).columns, 80)


def _group_line(group: str, choice: str | None) -> str:
    options = [f"*{o}" if o == choice else o for o in _options(group)]
    head = f"{group}: {GROUP_DOCS[group]}" if group in GROUP_DOCS else group
    listing = textwrap.fill(
        ", ".join(options), _width(), initial_indent="    ", subsequent_indent="    "
    )
    return f"{head}\n{listing}"


def _options(group: str) -> list[str]:
    """The group's options on the config search path (``hydra.searchpath`` additions
    too) when Hydra is running, else the packaged and stored ones."""
    if GlobalHydra.instance().is_initialized():
        loader = GlobalHydra.instance().config_loader()
        options = loader.get_group_options(group)
    else:
        options = group_options(group)
    return [o for o in options if not o.startswith("_")]


def _key_lines(node: DictConfig, prefix: str) -> list[str]:
    """``KEY=value  meaning`` for every key under ``node``, sections recursed into."""
    schema = OmegaConf.get_type(node)
    docs = attribute_docs(schema) if dataclasses.is_dataclass(schema) else {}
    lines: list[str] = []
    for key in node:
        if prefix == "" and key == "hydra":
            continue
        child = node._get_node(key)
        if _is_section(child):
            lines += _key_lines(child, f"{prefix}{key}.")  # type: ignore[arg-type]
            continue
        if key == "name" and prefix:
            continue  # the option's name is the group's choice, listed above
        setting = f"{prefix}{key}={_value(child)}"
        lines.append(_line(setting, _first_sentence(docs.get(str(key), ""))))
    return lines


def _is_section(node: Any) -> bool:
    """A nested typed config (a group's option, ``baselines``, ``collector.ray``)."""
    return (
        isinstance(node, DictConfig)
        and not node._is_none()
        and not node._is_missing()
        and not node._is_interpolation()
        and dataclasses.is_dataclass(OmegaConf.get_type(node))
    )


def _value(node: Any) -> str:
    """The value as typed on the command line (``null``, ``true``, ``[0,1]``), not
    resolved, cut to a few characters when long."""
    if isinstance(node, (DictConfig, ListConfig)):
        if node._is_missing():
            return "???"
        value = None if node._is_none() else OmegaConf.to_container(node, resolve=False)
    else:
        value = node._value()
    text = _spell(value)
    return text if len(text) <= _VALUE_CHARS else text[: _VALUE_CHARS - 3] + "..."


def _spell(value: Any) -> str:
    if value is None:
        return "null"
    if isinstance(value, bool):
        return str(value).lower()
    if isinstance(value, (list, tuple)):
        return "[" + ",".join(_spell(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{" + ",".join(f"{k}:{_spell(v)}" for k, v in value.items()) + "}"
    return str(value)


def _first_sentence(text: str) -> str:
    """The first sentence of a docstring entry, its reST literals (````M````) plain."""
    text = text.replace("``", "")
    match = _SENTENCE_END.search(text)
    return text[: match.start() + 1] if match else text


def _line(setting: str, doc: str) -> str:
    """One line: the setting, padded to a column, then as much of ``doc`` as fits."""
    head = f"  {setting}".ljust(_KEY_COLUMN - 1) + " "
    room = max(_width() - len(head), 20)
    if len(doc) > room:
        doc = doc[: room - 3].rstrip() + "..."
    return (head + doc).rstrip()
