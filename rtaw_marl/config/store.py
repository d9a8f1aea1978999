"""Registers every typed option with Hydra's ConfigStore, under ``schema/<group>/<name>``.

The YAML files in ``rtaw_marl/conf/`` are thin twins: each names its schema in its
defaults list (``- /schema/layout/shelves@_here_``) and adds only what differs (the
preset of ``layout=A``). The schemas make
composition typed: an unknown key or a value of the wrong type fails when Hydra composes
the config, and :func:`rtaw_marl.config.to_typed` turns the result into dataclasses.

Options made from a registry are stored here too, with no YAML file: the navigators
that change simulator keys (``navigator=sipp`` turns the completion noise off, from
``SIPPConfig.sim_defaults``), ``scenario=NAME`` and ``row=NAME``
(:mod:`rtaw_marl.config.scenarios`) and ``+zoo=NAME`` (the shipped policies' recipes).
"""

from __future__ import annotations

import itertools
import os
from collections.abc import Mapping
from pathlib import Path
from types import MappingProxyType
from typing import Any

import yaml
from hydra.core.config_store import ConfigStore
from hydra.core.object_type import ObjectType
from omegaconf import DictConfig, OmegaConf

from rtaw_marl.config.scenarios import register_scenarios
from rtaw_marl.evaluation.config import EvalConfig, RenderConfig, ViewConfig
from rtaw_marl.integrations.lorr.config import LoRRConfig
from rtaw_marl.models.config import MODELS
from rtaw_marl.scenarios.lorr import lorr_value
from rtaw_marl.sim.builder import DEFAULT_OPTIONS
from rtaw_marl.sim.config import SimConfig
from rtaw_marl.sim.options import LAYOUTS, NAVIGATORS, TASK_STREAMS
from rtaw_marl.training.config import CollectorConfig, PPOConfig, TrainConfig
from rtaw_marl.training.loggers.config import LOGGER_OPTIONS
from rtaw_marl.training.zoo import ZOO

__all__ = ["CONF_DIR", "GROUPS", "SETTINGS", "group_options", "register_configs"]

#: The packaged Hydra config folder (``rtaw_marl/conf``).
CONF_DIR = Path(__file__).resolve().parents[1] / "conf"

#: Config group -> option name -> schema dataclass.
GROUPS: dict[str, dict[str, type]] = {
    "sim": {"default": SimConfig},
    "layout": dict(LAYOUTS),
    "navigator": dict(NAVIGATORS),
    "tasks": dict(TASK_STREAMS),
    "model": dict(MODELS),
    "algo": {"ppo": PPOConfig},
    "collector": {"default": CollectorConfig},
    "logger": dict(LOGGER_OPTIONS),
}

#: The simulator groups' options a command starts from (``/setting/NAME`` in its
#: defaults list): ``default``, what :class:`~rtaw_marl.sim.builder.SimSpec` builds
#: (rtaw-eval, rtaw-train); ``watch``, the same with collision-free SIPP execution
#: (rtaw-render, rtaw-view: an episode to look at).
SETTINGS: Mapping[str, Mapping[str, str]] = MappingProxyType(
    {"default": DEFAULT_OPTIONS, "watch": {**DEFAULT_OPTIONS, "navigator": "sipp"}}
)

#: Primary configs -> their schema.
APPS: dict[str, type] = {
    "eval": EvalConfig,
    "train": TrainConfig,
    "render": RenderConfig,
    "view": ViewConfig,
    "lorr": LoRRConfig,
}

_registered = False


def register_configs() -> None:
    """Store every schema in Hydra's ConfigStore (once per process)."""
    global _registered
    if _registered:
        return
    # seeds='${range:0,20}' on the command line: the 20 evaluation seeds, without typing them.
    if not OmegaConf.has_resolver("range"):
        OmegaConf.register_new_resolver("range", lambda a, b: list(range(int(a), int(b))))
    # Run folders end in a run id, so two runs started in the same second never share
    # one. Cached: Hydra copies the cache into every job of a sweep, so the jobs of a
    # joblib sweep (other processes) agree with the folder their parent made.
    if not OmegaConf.has_resolver("run_id"):
        OmegaConf.register_new_resolver("run_id", _run_id, use_cache=True)
    # scenario=lorr: the robots, window and pool of a LoRR problem (scenarios.lorr).
    if not OmegaConf.has_resolver("lorr"):
        OmegaConf.register_new_resolver("lorr", lorr_value)
    store = ConfigStore.instance()
    for group, options in GROUPS.items():
        for name, schema in options.items():
            store.store(group=f"schema/{group}", name=name, node=_node(schema))
    for name, schema in APPS.items():
        store.store(group="schema", name=name, node=_node(schema))
    # navigator=sipp|cbs|pibt: also the simulator keys the option changes (the completion
    # noise off), from the option's own sim_defaults: one place for that rule.
    for name, option in NAVIGATORS.items():
        if option.sim_defaults:
            store.store(group="navigator", name=name, node=_navigator_node(name, option),
                        package="_global_")  # fmt: skip
    # The simulator groups' default options, from SimSpec's own (one place): each
    # command's defaults list includes one of SETTINGS.
    for name, options in SETTINGS.items():
        store.store(group="setting", name=name, node=_setting_node(options))
    # scenario=NAME and row=NAME: the scenario registry's entries (config.scenarios).
    register_scenarios(store)
    # rtaw-train -m +zoo=A_astar_m10,B_astar_m10: the shipped policies' recipes
    # (rtaw_marl.training.zoo) as one sweep. Continued entries are left out: they resume
    # a copy of their base's run folder.
    for recipe in (r for r in ZOO.values() if r.stage != "continued"):
        node = _zoo_node(recipe.overrides())
        store.store(group="zoo", name=recipe.name, node=node, package="_global_")
    _registered = True


def group_options(group: str) -> list[str]:
    """The options of config group ``group``, sorted: its packaged YAML files and the
    options stored from registries (``scenario``, ``row``, ``zoo``); empty for a group
    that does not exist."""
    register_configs()
    options = {p.stem for p in (CONF_DIR / group).glob("*.yaml")}
    store = ConfigStore.instance()
    if store.get_type(group) is ObjectType.GROUP:
        options |= {name.removesuffix(".yaml") for name in store.list(group)}
    return sorted(options)


def _setting_node(options: Mapping[str, str]) -> dict[str, Any]:
    """A :data:`SETTINGS` entry as a defaults list (a scenario or the command line may
    still choose another option of each group)."""
    return {"defaults": [{f"/{group}": name} for group, name in options.items()]}


def _navigator_node(name: str, option: type) -> dict[str, Any]:
    """``navigator=NAME`` for an option that changes simulator keys: its schema as the
    ``navigator`` group, and those keys (:attr:`NavigatorOption.sim_defaults`) in ``sim``,
    under the user's own overrides."""
    return {
        "defaults": [f"/schema/navigator/{name}@navigator", "_self_"],
        "sim": dict(option.sim_defaults),
    }


def _zoo_node(overrides: list[str]) -> dict[str, Any]:
    """A zoo recipe's ``rtaw-train`` overrides as a ``zoo`` option: its option
    choices (``layout=A``) become ``override /layout`` entries of a defaults list, its
    values (``sim.num_robots=10``) a nested dict."""
    defaults: list[Any] = []
    values: dict[str, Any] = {}
    for override in overrides:
        key, _, text = override.partition("=")
        if key in GROUPS or key == "scenario":
            defaults.append({f"override /{key}": text})
            continue
        *parents, leaf = key.split(".")
        node = values
        for part in parents:
            node = node.setdefault(part, {})
        node[leaf] = yaml.safe_load(text)
    return {"defaults": [*defaults, "_self_"], **values}


_runs_in_process = itertools.count()


def _run_id() -> str:
    """The process id; ``<pid>-<k>`` for the k-th later run of the same process."""
    k = next(_runs_in_process)
    return f"{os.getpid()}-{k}" if k else str(os.getpid())


def _node(schema: type) -> DictConfig | Any:
    node = OmegaConf.structured(schema)
    # Frozen dataclasses (SimConfig) come back read-only; overrides must still apply.
    OmegaConf.set_readonly(node, False)
    return node
