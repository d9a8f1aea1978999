"""What the command-line entry points share: the Hydra entry, one-line errors, and
building the simulator and the policies from a typed config."""

from __future__ import annotations

import os
import sys
from collections.abc import Callable
from functools import wraps
from pathlib import Path
from typing import Any, TypeVar

import hydra
from hydra.core.hydra_config import HydraConfig
from hydra.errors import HydraException
from hydra.experimental.callback import Callback
from hydra.types import RunMode
from omegaconf import DictConfig
from omegaconf.errors import OmegaConfBaseException

from rtaw_marl.cli.completion import narrowed_completion
from rtaw_marl.config import (
    CONF_DIR,
    check_overrides,
    check_renamed,
    compose,
    config_error,
    register_configs,
    to_typed,
)
from rtaw_marl.config.help import help_text, register_help
from rtaw_marl.errors import ConfigError, RtawError, extra_message, unknown_name
from rtaw_marl.evaluation.evaluate import SimPolicy
from rtaw_marl.policies import BASELINES
from rtaw_marl.policies.labels import checkpoint_labels
from rtaw_marl.policies.spec import PolicySpec
from rtaw_marl.policies.user import is_import_spec
from rtaw_marl.sim.core import WarehouseSim
from rtaw_marl.utils.atomic import atomic_write
from rtaw_marl.utils.signals import Interrupted, terminate_as_interrupt

__all__ = [
    "SweepFailures",
    "add_labelled",
    "check_distinct",
    "hydra_entry",
    "learned_files",
    "policies_from_cfg",
    "policy_names",
    "policy_specs",
    "typed",
]

#: A policy entry of a command (a :class:`PolicySpec`, or rtaw-lorr's run spec).
T = TypeVar("T")


def hydra_entry(config_name: str, task: Callable[[DictConfig], Any]) -> Callable[[], None]:
    """A console entry point: Hydra composes ``config_name`` and calls ``task``.

    A composition error (unknown key, option or value type) becomes one ``error: ...``
    line and exit status 2, like every other user error, instead of Hydra's multi-line
    report and status 1. In a sweep, a failed job prints its own line and the others
    still run; the sweep then exits 2 (:class:`SweepFailures`). An ``OSError`` (a path
    too long, no permission) is one line naming the file, as a user error is. Ctrl-C
    and SIGTERM print one ``interrupted`` line (what the task kept, if it says) and exit
    ``128 + signal`` (130, 143).
    """
    register_configs()
    register_help()

    @_exit_on_user_error
    @wraps(task)
    def checked(cfg: DictConfig) -> Any:
        # Inside the job Hydra's config holds this job's own overrides (one per job of
        # a sweep): a boolean key given "off" or "1" is refused before the task runs.
        check_overrides(cfg, HydraConfig.get().overrides.task)
        return task(cfg)

    hydra_main = hydra.main(config_path=str(CONF_DIR), config_name=config_name, version_base="1.3")(
        checked
    )

    def main() -> None:
        previous = os.environ.get("HYDRA_FULL_ERROR")
        # Let composition errors reach this frame instead of Hydra's own report.
        os.environ["HYDRA_FULL_ERROR"] = "1"
        try:
            # An old key (eval.every_frames) names its new one, before Hydra's "not in struct".
            check_renamed(config_name, sys.argv[1:])
            if _help_asked(sys.argv[1:]):
                _print_help(config_name, sys.argv[1:])
                return
            # -sc: a bad request is one line; a query offers only this command's groups.
            with terminate_as_interrupt(), narrowed_completion(config_name, sys.argv[1:]):
                hydra_main()
        except (HydraException, OmegaConfBaseException, RtawError, OSError) as exc:
            print(f"error: {_one_line(exc)}", file=sys.stderr)
            sys.exit(2)
        except KeyboardInterrupt as exc:
            print(f"interrupted{': ' + str(exc) if str(exc) else ''}", file=sys.stderr)
            sys.exit(exc.exit_status if isinstance(exc, Interrupted) else 130)
        finally:
            if previous is None:
                os.environ.pop("HYDRA_FULL_ERROR", None)
            else:
                os.environ["HYDRA_FULL_ERROR"] = previous

    main.__doc__ = f"Console entry point of the {config_name!r} config."
    return main


def _one_line(exc: BaseException) -> str:
    """The user's line for an error: an ``OSError`` from the file system (a path too
    long, a full disk, no permission) names the path and the reason."""
    # Hydra's MissingConfigException is an OSError too: its own line comes first.
    if isinstance(exc, OSError) and not isinstance(exc, (RtawError, HydraException)):
        where = f": {exc.filename}" if exc.filename else ""
        return f"{exc.strerror or exc}{where}".splitlines()[0]
    return str(config_error(exc)).splitlines()[0]


#: Written into a sweep job's folder when the job fails on a user error.
FAILED_MARKER = "FAILED"


def _help_asked(args: list[str]) -> bool:
    return any(arg in ("--help", "-h") for arg in args)


def _print_help(config_name: str, args: list[str]) -> None:
    """``--help``: the command's own page (:func:`rtaw_marl.config.help.help_text`) for
    the config its overrides compose to. Composed here rather than by Hydra, whose help
    first lists every option of every config group, a listing the page does not show
    (20 s of the 21 s ``rtaw-eval --help`` took)."""
    overrides = [arg for arg in args if "=" in arg and not arg.startswith("-")]
    cfg = compose(config_name, overrides, return_hydra_config=True)
    print(help_text(config_name, cfg), end="")


def _exit_on_user_error(fn: Callable[[DictConfig], Any]) -> Callable[[DictConfig], Any]:
    """Turn user errors into one ``error: ...`` line on stderr and exit status 2.

    An ``OSError`` that escapes the task (the file system's: a path too long, no
    permission, a folder that cannot be made) counts as one: its line names the file.

    In a sweep the line names the job (number and overrides), and the job returns
    instead of ending the process, so the other jobs still run; it leaves a ``FAILED``
    file in its folder, from which :class:`SweepFailures` sets the sweep's exit status.
    """

    @wraps(fn)
    def wrapper(cfg: DictConfig) -> Any:
        try:
            return fn(cfg)
        except (RtawError, HydraException, OmegaConfBaseException, OSError) as exc:
            message = _one_line(exc)
            job = _sweep_job()
            if job is None:
                print(f"error: {message}", file=sys.stderr)
                sys.exit(2)
            print(f"error: {job}: {message}", file=sys.stderr)
            folder = Path(HydraConfig.get().runtime.output_dir)
            atomic_write(
                folder / FAILED_MARKER, lambda fh: fh.write(f"{job}: {message}\n".encode())
            )
            return None

    return wrapper


def _sweep_job() -> str | None:
    """``job 3 (sim.num_robots=0)`` inside a multirun job, else ``None``."""
    if not HydraConfig.initialized():
        return None
    hydra_cfg = HydraConfig.get()
    if hydra_cfg.mode != RunMode.MULTIRUN:
        return None
    return f"job {hydra_cfg.job.num} ({' '.join(hydra_cfg.overrides.task)})"


class SweepFailures(Callback):
    """Hydra callback (``hydra.callbacks`` of the CLI configs): after a sweep, exit 2
    if any job failed, with one line that counts them (each printed its own)."""

    def on_multirun_end(self, config: DictConfig, **kwargs: Any) -> None:
        sweep_dir = Path(str(config.hydra.sweep.dir))
        failed = sorted(sweep_dir.glob(f"*/{FAILED_MARKER}"))
        if failed:
            jobs = len(
                [p for p in sweep_dir.iterdir() if p.is_dir() and not p.name.startswith(".")]
            )
            print(
                f"error: {len(failed)} of {jobs} jobs failed (their errors are above and in "
                f"{sweep_dir}/*/{FAILED_MARKER})",
                file=sys.stderr,
            )
            # SystemExit, not an exception: Hydra turns callback exceptions into warnings.
            raise SystemExit(2)


def typed(cfg: DictConfig | Any) -> Any:
    """The typed dataclass of a composed config (a typed config passes through)."""
    return to_typed(cfg) if isinstance(cfg, DictConfig) else cfg


#: The old name of ``policy=pretrained``; still accepted, with a one-line warning.
_OLD_PRETRAINED = "rtaw"


def policy_names(names: list[str]) -> list[str]:
    """``names`` with the deprecated ``rtaw`` spelled ``pretrained`` (one warning line:
    ``rtaw`` is also the package and the paper's network, ``model=rtaw``)."""
    if _OLD_PRETRAINED not in names:
        return names
    print(
        "warning: policy=rtaw is deprecated, use policy=pretrained (a shipped policy "
        "named by pretrained=...)",
        file=sys.stderr,
    )
    return ["pretrained" if n == _OLD_PRETRAINED else n for n in names]


def policy_specs(cfg: Any, names: list[str]) -> dict[str, PolicySpec]:
    """Label -> :class:`~rtaw_marl.policies.spec.PolicySpec` for a command's policies:
    rules by name, your own by ``module:Name`` (label ``Name``), ``checkpoint`` (one per
    path in ``cfg.checkpoint``) and ``pretrained`` (one per shipped policy named in
    ``cfg.pretrained``; ``rtaw`` is its deprecated name). Nothing is loaded yet.

    Raises:
        ConfigError: ``checkpoint``/``pretrained`` without its values or the reverse, an
            unknown rule, or two policies under one label.
    """
    names = policy_names(names)
    search = getattr(cfg, "search", None)  # rtaw-view and rtaw-lorr do not search
    sources = {"checkpoint": as_list(cfg.checkpoint), "pretrained": as_list(cfg.pretrained)}
    if search is not None:
        sources["search"] = as_list(search.policy)
    sources["matched"] = as_list(getattr(cfg, "matched", None))
    for option in sources:
        key = "search.policy" if option == "search" else option
        if option in names and not sources[option]:
            raise ConfigError(f"policy={option} needs {key}=... (one value or a list)")
        if sources[option] and option not in names:
            raise ConfigError(f"{key}=... given but policy does not include '{option}'")
    specs: dict[str, PolicySpec] = {}
    for name in names:
        if is_import_spec(name):
            add_labelled(specs, name.rpartition(":")[2], PolicySpec("import", name))
        elif name not in sources:
            if name not in BASELINES:
                valid = [*BASELINES, *sources, "module:Name"]
                raise unknown_name("policy", name, valid)
            add_labelled(specs, name, PolicySpec.rule(name, cfg.baselines))
        else:
            k = cfg.candidates
            if name == "matched" and k is None:
                raise ConfigError("policy=matched needs candidates=K (for example candidates=32)")
            params = () if name != "search" else _search_params(search)
            for label, source in _learned(name, sources[name], k).items():
                add_labelled(specs, label, PolicySpec(name, source, params, candidates=k))
    return specs


def policies_from_cfg(cfg: Any, names: list[str], sim: WarehouseSim) -> dict[str, SimPolicy]:
    """The policies of :func:`policy_specs`, built: rules bound to ``sim``, networks
    loaded with ``cfg.torch_threads``, user policies imported."""
    policies = {}
    for label, spec in policy_specs(cfg, names).items():
        try:
            policies[label] = spec.build(sim, label, torch_threads=int(cfg.torch_threads))
        except ModuleNotFoundError as exc:  # an install without the train extra
            raise ConfigError(extra_message(f"policy={spec.kind}", "train", exc.name)) from None
    return policies


def add_labelled(specs: dict[str, T], label: str, spec: T) -> None:
    """Add ``spec`` under ``label``; two policies under one label is an error (a policy
    named twice would silently run once)."""
    if label in specs:
        raise ConfigError(f"two policies are labelled {label!r}; each label names one policy")
    specs[label] = spec


def check_distinct(option: str, values: list[str]) -> None:
    """Refuse a ``checkpoint=``/``pretrained=`` list that names one value twice."""
    twice = sorted({v for v in values if values.count(v) > 1})
    if twice:
        raise ConfigError(f"{option}= names {twice[0]!r} twice; each value names one policy")


def learned_files(cfg: Any, names: list[str]) -> dict[str, Path]:
    """The file each learned policy of :func:`policies_from_cfg` was loaded from, by its
    label (what an evaluation journal hashes); call it once they have loaded."""
    specs = policy_specs(cfg, names)
    return {label: path for label, spec in specs.items() if (path := spec.path()) is not None}


def _learned(option: str, sources: list[str], candidates: int | None) -> dict[str, str]:
    """Label -> source for each ``checkpoint=`` value (a path, or a shipped name) or
    ``pretrained=`` value (a shipped name only, never a file).

    Labels are short: a shipped policy's name, a checkpoint file's
    :func:`~rtaw_marl.policies.labels.checkpoint_labels`; ``@k<K>`` is added with
    ``candidates=K`` (a policy restricted to K candidates is another policy, with its own
    journal entries).
    """
    check_distinct("search.policy" if option == "search" else option, sources)
    tag = "" if candidates is None else f"@k{candidates}"
    labels = sources if option == "pretrained" else checkpoint_labels(sources)
    if option in ("search", "matched"):
        tag += f"+{option}"
    return {f"{label}{tag}": source for label, source in zip(labels, sources, strict=True)}


def _search_params(search: Any) -> tuple[tuple[str, Any], ...]:
    """A ``search`` section's ``(key, value)`` pairs for :class:`PolicySpec`."""
    keys = ("horizon", "leaf", "propose", "width")
    return tuple(sorted((k, _plain(getattr(search, k))) for k in keys))


def _plain(value: Any) -> Any:
    """A list option as a tuple (a spec is frozen and hashed), a scalar as it is."""
    return value if value is None or isinstance(value, (str, int, float)) else tuple(value)


def as_list(value: object) -> list[str]:
    """``None`` -> ``[]``, a scalar -> ``[str(value)]``, a list -> its items as strings."""
    if value is None:
        return []
    return [str(value)] if isinstance(value, (str, int)) else [str(v) for v in value]
