"""``rtaw-lorr``: schedulers inside the League of Robot Runners' own simulator.

Builds LoRR's 2024 start kit once per machine (a few minutes; system packages installed
where missing), then runs ``lifelong`` on a problem once per scheduler, with the kit's
default planner, and writes one ``results.json``: tasks finished, schedule and planner
errors, entry timeouts, and each rtaw_marl scheduler's decisions and deferred robots.

Examples::

    rtaw-lorr build_only=true
    rtaw-lorr problem=../shared/maps/lorr/warehouse_large_5000.json \\
        policy=[lorr_default,mpdm,batch,pretrained] pretrained=generalist_plus candidates=32
    rtaw-lorr problem=P.json policy=checkpoint checkpoint=runs/x/checkpoints/best.pt \\
        timesteps=5000 plan_time_ms=1000
"""

from __future__ import annotations

import dataclasses
import json
import os
import re
from pathlib import Path
from typing import Any

from hydra.core.hydra_config import HydraConfig
from omegaconf import DictConfig

from rtaw_marl.cli.common import as_list, hydra_entry, policy_names, typed
from rtaw_marl.errors import ConfigError, unknown_name
from rtaw_marl.integrations.lorr.config import LORR_DEFAULT, LoRRConfig
from rtaw_marl.integrations.lorr.entry import RunSpec
from rtaw_marl.integrations.lorr.kit import build_kit
from rtaw_marl.integrations.lorr.run import LoRRRun, run_lifelong
from rtaw_marl.policies import BASELINES
from rtaw_marl.policies.labels import checkpoint_labels
from rtaw_marl.policies.user import import_policy, is_import_spec
from rtaw_marl.sim.lorr import read_problem
from rtaw_marl.utils.atomic import atomic_write
from rtaw_marl.utils.runs import check_writable_file

#: Rules that cannot schedule inside another simulator.
_NO_OUTSIDE = {"hindsight": "hindsight needs the episode's future, which LoRR does not tell"}


def run(cfg: DictConfig | LoRRConfig) -> dict[str, LoRRRun]:
    """Build the kit, run each scheduler, print and write the results."""
    cfg = typed(cfg)
    if cfg.build_only:
        for variant in ("python", "default"):
            build_kit(variant, cfg.kit, cfg.cache)
        return {}
    if cfg.problem is None:
        raise ConfigError("rtaw-lorr needs problem=FILE.json (a LoRR 2024 problem)")
    problem = read_problem(str(cfg.problem))
    folder = Path(HydraConfig.get().runtime.output_dir)
    output = check_writable_file(cfg.output or folder / "results.json")
    schedulers = _schedulers(cfg, str(problem.path))
    runs: dict[str, LoRRRun] = {}
    for label, spec in schedulers.items():
        build = build_kit("default" if spec is None else "python", cfg.kit, cfg.cache)
        print(f"{label}: lifelong, {cfg.timesteps} timesteps at {cfg.plan_time_ms} ms ...")
        runs[label] = run_lifelong(
            build, problem.path, folder / _folder_name(label), spec, label, cfg.timesteps,
            cfg.plan_time_ms, cfg.preprocess_time_ms,
        )  # fmt: skip
        print(_line(runs[label], runs))
    results = {
        "config": dataclasses.asdict(cfg),
        "problem": str(problem.path),
        "simulator": "lorr-start-kit-2.1.2",
        "runs": {k: dataclasses.asdict(v) for k, v in runs.items()},
    }
    text = json.dumps(results, indent=1)
    atomic_write(output, lambda fh: fh.write(text.encode()))
    print(f"results: {output}")
    return runs


def _schedulers(cfg: LoRRConfig, problem: str) -> dict[str, RunSpec | None]:
    """Label -> run spec (``None``: the kit's own scheduler), checked before any run."""
    names = policy_names(as_list(cfg.policy))
    if not names:
        raise ConfigError("policy must name at least one scheduler")
    sources = {"checkpoint": as_list(cfg.checkpoint), "pretrained": as_list(cfg.pretrained)}
    for option, given in sources.items():
        if option in names and not given:
            raise ConfigError(f"policy={option} needs {option}=... (one value or a list)")
    valid = [LORR_DEFAULT, *(b for b in BASELINES if b not in _NO_OUTSIDE), *sources]
    common = {
        "problem": problem,
        "timesteps": int(cfg.timesteps),
        "share": float(cfg.share),
        "baselines": dataclasses.asdict(cfg.baselines),
    }
    out: dict[str, RunSpec | None] = {}
    for name in names:
        if name in _NO_OUTSIDE:
            raise ConfigError(f"policy={name}: {_NO_OUTSIDE[name]}")
        if is_import_spec(name):
            # Imported here too, so a bad module or name is one line before any run.
            label, _ = import_policy(name)
            out[label] = RunSpec(policy=name, stats="stats.json", search_path=os.getcwd(), **common)
            continue
        if name not in valid:
            raise unknown_name("policy", name, valid)
        if name == LORR_DEFAULT:
            out[name] = None
        elif name in sources:
            out.update(_learned(cfg, name, sources[name], common))
        else:
            out[name] = RunSpec(policy=name, stats="stats.json", **common)
    return out


def _learned(cfg: LoRRConfig, option: str, given: list[str], common: dict[str, Any]) -> dict:
    from rtaw_marl.policies.network import checkpoint_path

    tag = "" if cfg.candidates is None else f"@k{cfg.candidates}"
    out = {}
    for source, label in zip(given, checkpoint_labels(given), strict=True):
        # Resolved here, so a bad name or file is one line before any run.
        path = checkpoint_path(source)
        out[f"{label}{tag}"] = RunSpec(
            policy=option, source=str(path), candidates=cfg.candidates, stats="stats.json",
            **common,
        )  # fmt: skip
    return out


def _folder_name(label: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.@-]+", "_", label)


def _line(result: LoRRRun, runs: dict[str, LoRRRun]) -> str:
    base = runs.get(LORR_DEFAULT)
    vs = ""
    if base is not None and result is not base and base.tasks_finished:
        gain = 100.0 * (result.tasks_finished / base.tasks_finished - 1)
        vs = f", {gain:+.1f}% vs {LORR_DEFAULT}"
    sched = result.scheduler
    extra = ""
    if sched:
        ms = 1000.0 * float(sched.get("seconds", 0.0)) / max(1, int(sched.get("calls", 1)))
        extra = f", {sched.get('deferred', 0)} deferred, scheduler {ms:.1f} ms/timestep"
    return (
        f"  {result.policy}: {result.tasks_finished} tasks finished in {result.timesteps} "
        f"timesteps{vs}; {result.schedule_errors} schedule errors, {result.planner_errors} "
        f"planner errors, {result.timeouts} timeouts{extra}; {result.wall_s:.0f} s"
    )


main = hydra_entry("lorr", run)


if __name__ == "__main__":
    main()
