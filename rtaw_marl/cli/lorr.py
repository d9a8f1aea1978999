"""``rtaw-lorr``: schedulers inside the League of Robot Runners' own simulator.

Builds LoRR's 2024 start kit once per machine (a few minutes; ``make lorr-kit`` installs
the system packages it needs), then runs ``lifelong`` on a problem once per scheduler,
with the kit's default planner, and writes one ``results.json``: tasks finished, schedule
and planner errors, entry timeouts, and each rtaw_marl scheduler's decisions and deferred
robots. The file is rewritten after each scheduler: a stop (Ctrl-C, SIGTERM) keeps the
finished ones, and the same command with ``resume=true`` runs the rest.

Examples::

    rtaw-lorr build_only=true
    rtaw-lorr problem=../shared/maps/lorr/warehouse_large_5000.json \\
        policy=[lorr_default,mpdm,batch,pretrained] pretrained=generalist_plus candidates=32
    rtaw-lorr problem=P.json policy=checkpoint checkpoint=runs/x/checkpoints/best.pt \\
        timesteps=5000 plan_time_ms=1000
    rtaw-lorr problem=P.json policy=[mpdm,rbts] output=runs/lorr.json resume=true
"""

from __future__ import annotations

import dataclasses
import os
import re
import shutil
import signal
from pathlib import Path
from typing import Any

from hydra.core.hydra_config import HydraConfig
from omegaconf import DictConfig

from rtaw_marl.cli.common import (
    add_labelled,
    as_list,
    check_distinct,
    hydra_entry,
    policy_names,
    typed,
)
from rtaw_marl.errors import ConfigError, unknown_name
from rtaw_marl.integrations.lorr.config import LORR_DEFAULT, LoRRConfig
from rtaw_marl.integrations.lorr.entry import RunSpec
from rtaw_marl.integrations.lorr.kit import build_kit
from rtaw_marl.integrations.lorr.planner import PlannerSpec
from rtaw_marl.integrations.lorr.results import describe, finished_runs, write_results
from rtaw_marl.integrations.lorr.run import RUN_FILES, LoRRRun, run_lifelong
from rtaw_marl.policies import BASELINES
from rtaw_marl.policies.labels import checkpoint_labels
from rtaw_marl.policies.user import import_policy, is_import_spec
from rtaw_marl.sim.lorr import LoRRProblem, read_problem
from rtaw_marl.sim.options import PIBTConfig
from rtaw_marl.utils.runs import claim_file, claim_folder
from rtaw_marl.utils.signals import Interrupted

#: Rules that cannot schedule inside another simulator.
_NO_OUTSIDE = {"hindsight": "hindsight needs the episode's future, which LoRR does not tell"}


def run(cfg: DictConfig | LoRRConfig) -> dict[str, LoRRRun]:
    """Build the kit, run each scheduler, print and write the results.

    Everything is checked before the first ``lifelong`` run: the problem in full, each
    scheduler (checkpoints loaded), the output and run folders (claimed). results.json
    is rewritten after each scheduler, so a stop keeps the finished ones and
    ``resume=true`` runs the rest.
    """
    cfg = typed(cfg)
    if cfg.build_only:
        for variant in ("python", "planner", "default"):
            build_kit(variant, cfg.kit, cfg.cache)
        return {}
    if cfg.problem is None:
        raise ConfigError("rtaw-lorr needs problem=FILE.json (a LoRR 2024 problem)")
    problem = read_problem(str(cfg.problem))
    folder = Path(HydraConfig.get().runtime.output_dir)
    output = Path(cfg.output) if cfg.output else folder / "results.json"
    schedulers = _schedulers(cfg, str(problem.path))
    with claim_file(output) as output, claim_folder(folder, "hydra.run.dir") as folder:
        runs = finished_runs(output, cfg, problem) if cfg.resume else {}
        runs = {label: runs[label] for label in schedulers if label in runs}
        todo = {label: spec for label, spec in schedulers.items() if label not in runs}
        _clear_run_folders(folder, list(todo), cfg.resume)
        if runs:
            print(f"resume: {describe(runs)} kept from {output}")
        print(_estimate(cfg, len(todo)))
        try:
            for label, spec in todo.items():
                runs[label] = _run_one(cfg, problem, folder, label, spec)
                print(_line(runs[label], runs))
                write_results(output, cfg, problem, runs, [k for k in todo if k not in runs])
        except KeyboardInterrupt as exc:
            raise _stopped(exc, cfg, output, runs, todo) from None
    write_results(output, cfg, problem, {k: runs[k] for k in schedulers}, [])
    print(f"results: {output}")
    return runs


def _run_one(
    cfg: LoRRConfig,
    problem: LoRRProblem,
    folder: Path,
    label: str,
    spec: RunSpec | PlannerSpec | None,
) -> LoRRRun:
    variant = "planner" if isinstance(spec, PlannerSpec) else "python"
    build = build_kit("default" if spec is None else variant, cfg.kit, cfg.cache)
    print(f"{label}: lifelong, {cfg.timesteps} timesteps at {cfg.plan_time_ms} ms ...")
    return run_lifelong(
        build, problem.path, folder / _folder_name(label), spec, label, cfg.timesteps,
        cfg.plan_time_ms, cfg.preprocess_time_ms,
    )  # fmt: skip


def _clear_run_folders(folder: Path, labels: list[str], resume: bool) -> None:
    """Make room for the schedulers to run in ``folder`` (held by this run).

    A scheduler's folder left by an earlier run is refused (its output would mix with
    the new one), except with ``resume=true``, where it is what a stopped run left: it
    is removed if it holds only what ``lifelong`` writes, never anything else.
    """
    for label in labels:
        sub = folder / _folder_name(label)
        if not sub.exists():
            continue
        if not resume:
            raise ConfigError(
                f"{sub} already holds a run of {label}: give another hydra.run.dir, or "
                "resume=true with the same output to continue that run"
            )
        extra = sorted(p.name for p in sub.iterdir() if p.name not in RUN_FILES)
        if not sub.is_dir() or sub.is_symlink() or extra:
            raise ConfigError(
                f"resume=true: {sub} holds files lifelong does not write ({', '.join(extra)}); "
                "move it away or give another hydra.run.dir"
            )
        shutil.rmtree(sub)


def _estimate(cfg: LoRRConfig, runs: int) -> str:
    """The run's length: LoRR's planner uses its whole time limit every timestep."""
    seconds = runs * cfg.timesteps * cfg.plan_time_ms / 1000.0
    span = f"{seconds / 3600:.1f} h" if seconds >= 3600 else f"{seconds / 60:.0f} min"
    return (
        f"rtaw-lorr: {runs} lifelong run(s) of {cfg.timesteps} timesteps at "
        f"{cfg.plan_time_ms} ms each: about {span} (the planner uses its whole time limit)"
    )


def _stopped(
    exc: KeyboardInterrupt,
    cfg: LoRRConfig,
    output: Path,
    runs: dict[str, LoRRRun],
    todo: dict[str, Any],
) -> Interrupted:
    """The one line of a stop: what was kept and the command that continues."""
    signum = exc.signum if isinstance(exc, Interrupted) else signal.SIGINT
    left = [label for label in todo if label not in runs]
    kept = f"{describe(runs)} kept in {output}" if runs else "no scheduler had finished"
    again = "resume=true" + ("" if cfg.output else f" output={output}")
    rest = describe(dict.fromkeys(left))
    return Interrupted(
        f"stopped: {kept}; run the same command with {again} to run {rest}", signum=signum
    )


def _schedulers(cfg: LoRRConfig, problem: str) -> dict[str, RunSpec | PlannerSpec | None]:
    """Label -> run spec (``None``: the kit's own scheduler and planner), checked before
    any run."""
    names = policy_names(as_list(cfg.policy))
    if not names:
        raise ConfigError("policy must name at least one scheduler")
    if cfg.planner == "pibt":
        if names != [LORR_DEFAULT]:
            raise ConfigError(
                "planner=pibt runs under the kit's default scheduler (LoRR's planner "
                f"track): give policy={LORR_DEFAULT}, got policy={','.join(names)}"
            )
        nav = PIBTConfig()
        spec = PlannerSpec(
            problem=problem, stats="stats.json", timesteps=int(cfg.timesteps),
            patience=nav.patience, guidance=nav.guidance, guide_replans=nav.guide_replans,
        )  # fmt: skip
        return {f"{LORR_DEFAULT}+pibt": spec}
    sources = {
        "checkpoint": as_list(cfg.checkpoint),
        "pretrained": as_list(cfg.pretrained),
        "matched": as_list(cfg.matched),
    }
    for option, given in sources.items():
        if option in names and not given:
            raise ConfigError(f"policy={option} needs {option}=... (one value or a list)")
        if given and option not in names:
            raise ConfigError(f"{option}=... given but policy does not include '{option}'")
    if "matched" in names and cfg.candidates is None:
        raise ConfigError("policy=matched needs candidates=K (for example candidates=32)")
    # lorr_default is the kit's own C++ scheduler here (the rule of that name mirrors it
    # in the own simulator).
    rules = (b for b in BASELINES if b not in _NO_OUTSIDE and b != LORR_DEFAULT)
    valid = [LORR_DEFAULT, *rules, *sources]
    common = {
        "problem": problem,
        "timesteps": int(cfg.timesteps),
        "share": float(cfg.share),
        "overflow": cfg.overflow,
        "baselines": dataclasses.asdict(cfg.baselines),
    }
    out: dict[str, RunSpec | None] = {}
    for name in names:
        if name in _NO_OUTSIDE:
            raise ConfigError(f"policy={name}: {_NO_OUTSIDE[name]}")
        if is_import_spec(name):
            # Imported here too, so a bad module or name is one line before any run.
            label, _ = import_policy(name)
            spec = RunSpec(policy=name, stats="stats.json", search_path=os.getcwd(), **common)
            _add(out, {label: spec})
            continue
        if name not in valid:
            raise unknown_name("policy", name, valid)
        if name == LORR_DEFAULT:
            _add(out, {name: None})
        elif name in sources:
            _add(out, _learned(cfg, name, sources[name], common))
        else:
            _add(out, {name: RunSpec(policy=name, stats="stats.json", **common)})
    return out


def _add(out: dict[str, RunSpec | None], new: dict[str, RunSpec | None]) -> None:
    """Add schedulers; one named twice is refused (it would silently run once)."""
    for label, spec in new.items():
        add_labelled(out, label, spec)


def _learned(cfg: LoRRConfig, option: str, given: list[str], common: dict[str, Any]) -> dict:
    from rtaw_marl.policies.network import checkpoint_path, load_policy

    check_distinct(option, given)
    tag = "" if cfg.candidates is None else f"@k{cfg.candidates}"
    tag += "+matched" if option == "matched" else ""
    out = {}
    for source, label in zip(given, checkpoint_labels(given), strict=True):
        # Resolved and loaded here (safely, as inside lifelong), so a missing, damaged
        # or crafted file is one line before any run, not an error after earlier ones.
        path = checkpoint_path(source)
        load_policy(str(path), candidates=cfg.candidates)
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
    if "mismatches" in sched:  # the own executor as planner (planner=pibt)
        ms = 1000.0 * float(sched.get("seconds", 0.0)) / max(1, int(sched.get("timesteps", 1)))
        extra = f", {sched['mismatches']} mismatches, planner {ms:.1f} ms/timestep"
    elif sched:
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
