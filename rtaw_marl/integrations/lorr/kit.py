"""LoRR's 2024 start kit, built once per machine into a cache folder.

Three builds of the same sources (v2.1.2, MIT, ``../shared/lorr/start-kit-v2.1.2``
beside the project or ``RTAW_LORR_KIT``): ``python``, the scheduler track with Python
(the kit's default planner; ``pyTaskScheduler.py`` schedules), which serves rtaw_marl
policies; ``planner``, the planner track with Python (the kit's default scheduler;
``pyMAPFPlanner.py`` plans), which serves the own executor; and ``default``, the kit's
own C++ entry (its default scheduler and planner), LoRR's reference. A build lives in
``~/.cache/rtaw_marl/lorr/<variant>-<hash>`` (``RTAW_LORR_CACHE``), keyed by the kit's
sources, the Python and pybind11: made under a file lock in a temporary folder, then
renamed, so concurrent callers (test workers) build it once and never see half a build.

What it needs: cmake, a C++17 compiler, make, Boost (program_options, system,
filesystem, log) and pybind11 (``pip install 'rtaw_marl[lorr]'``). The library installs
no system package: a missing one is an error naming the ``apt-get`` command, and
``make lorr-kit`` installs them (``--missing`` prints their Debian names).
"""

from __future__ import annotations

import fcntl
import hashlib
import os
import shutil
import subprocess
import sys
import sysconfig
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

from rtaw_marl.errors import ConfigError

__all__ = ["KIT_VERSION", "KitBuild", "StartKitError", "build_kit", "kit_source", "set_track"]

KIT_VERSION = "2.1.2"
VARIANTS = ("python", "default", "planner")
#: The Python track of each Python build (``python/set_track.bash``'s argument).
_PYTHON_TRACK = {"python": "scheduler", "planner": "planner"}
#: What the build needs from the system: a file that shows it, and its Debian package.
_SYSTEM = (
    ("cmake", "cmake"),
    ("c++", "g++"),
    ("make", "make"),
    ("/usr/include/boost/program_options.hpp", "libboost-program-options-dev"),
    ("/usr/include/boost/system/error_code.hpp", "libboost-system-dev"),
    ("/usr/include/boost/filesystem.hpp", "libboost-filesystem-dev"),
    ("/usr/include/boost/log/core.hpp", "libboost-log-dev"),
)
#: The kit's files a build reads (not its example problems).
_SOURCES = ("CMakeLists.txt", "version.txt", "src", "inc", "default_planner", "python")


class StartKitError(ConfigError):
    """The start kit is missing, cannot be built, or a run of it failed."""


@dataclass(frozen=True)
class KitBuild:
    """A finished build.

    Attributes:
        variant: ``python``, ``planner`` or ``default``.
        root: Its folder (the kit's sources and ``build/``).
    """

    variant: str
    root: Path

    @property
    def lifelong(self) -> Path:
        """The simulator executable."""
        return self.root / "build" / "lifelong"

    @property
    def module_dir(self) -> Path:
        """Where the ``MAPF`` Python module of a Python build is."""
        return self.root / "build"


def kit_source(path: str | Path | None = None) -> Path:
    """The start kit's sources: ``path``, ``RTAW_LORR_KIT``, or ``../shared`` beside the
    project.

    Raises:
        StartKitError: No start kit there (the message says where it looked).
    """
    if path is None:
        path = os.environ.get("RTAW_LORR_KIT")
    if path is None:
        project = Path(__file__).resolve().parents[3]
        path = project.parent / "shared" / "lorr" / f"start-kit-v{KIT_VERSION}"
    path = Path(path)
    if not (path / "CMakeLists.txt").is_file() or not (path / "python").is_dir():
        raise StartKitError(
            f"LoRR start kit v{KIT_VERSION} not found at {path} (give kit=PATH or set "
            "RTAW_LORR_KIT)"
        )
    return path.resolve()


def cache_root(path: str | Path | None = None) -> Path:
    """Where builds are cached: ``path``, ``RTAW_LORR_CACHE`` or ``~/.cache/rtaw_marl/lorr``."""
    if path is None:
        path = os.environ.get("RTAW_LORR_CACHE") or Path.home() / ".cache" / "rtaw_marl" / "lorr"
    return Path(path)


def build_kit(
    variant: str = "python",
    source: str | Path | None = None,
    cache: str | Path | None = None,
    log: Callable[[str], None] = lambda line: print(line, file=sys.stderr),
) -> KitBuild:
    """The cached build of ``variant``, made first if missing (a few minutes).

    Raises:
        StartKitError: Unknown variant, no kit, a missing tool that cannot be installed,
            or a failed build step (the message names the step and its log).
    """
    if variant not in VARIANTS:
        raise StartKitError(f"unknown start kit build {variant!r}; valid: {', '.join(VARIANTS)}")
    src = kit_source(source)
    pybind_dir = _pybind11_dir() if variant in _PYTHON_TRACK else None
    key = _build_key(src, variant, pybind_dir)
    root = cache_root(cache)
    build = KitBuild(variant, root / f"{variant}-{key}")
    if build.lifelong.is_file():
        return build
    root.mkdir(parents=True, exist_ok=True)
    with _locked(root / f".{variant}.lock"):
        if build.lifelong.is_file():  # another process built it meanwhile
            return build
        check_system_packages()
        log(f"building LoRR's start kit v{KIT_VERSION} ({variant}) into {build.root} ...")
        tmp = root / f".{build.root.name}.tmp"
        shutil.rmtree(tmp, ignore_errors=True)
        _copy_sources(src, tmp)
        _compile(tmp, variant, pybind_dir)
        os.replace(tmp, build.root)
    log(f"built {build.lifelong}")
    return build


def missing_packages() -> list[str]:
    """The Debian packages of the build's tools and libraries that are missing."""
    missing = []
    for probe, package in _SYSTEM:
        found = Path(probe).is_file() if probe.startswith("/") else shutil.which(probe)
        if not found:
            missing.append(package)
    return missing


def check_system_packages() -> None:
    """Refuse to build when the build's tools or libraries are missing.

    Raises:
        StartKitError: Packages are missing; the message names the command that installs
            them (``make lorr-kit`` runs it).
    """
    missing = missing_packages()
    if missing:
        command = f"sudo apt-get install -y --no-install-recommends {' '.join(missing)}"
        raise StartKitError(
            f"the start kit needs {', '.join(missing)}: install them ({command}), or run "
            "make lorr-kit in the repository"
        )


def _pybind11_dir() -> str:
    try:
        import pybind11
    except ModuleNotFoundError:
        raise StartKitError(
            "the start kit's Python build needs pybind11: pip install 'rtaw_marl[lorr]'"
        ) from None
    return str(pybind11.get_cmake_dir())


def _build_key(src: Path, variant: str, pybind_dir: str | None) -> str:
    digest = hashlib.sha256(f"{variant}|{sys.version}|{pybind_dir}".encode())
    for name in _SOURCES:
        for file in sorted((src / name).rglob("*")) if (src / name).is_dir() else [src / name]:
            if file.is_file() and "tmp" not in file.relative_to(src).parts:
                digest.update(str(file.relative_to(src)).encode())
                digest.update(file.read_bytes())
    return digest.hexdigest()[:12]


def _copy_sources(src: Path, dest: Path) -> None:
    dest.mkdir(parents=True)
    for name in _SOURCES:
        if (src / name).is_dir():
            # A tmp/ the kit's set_track.bash left in the sources is not ours.
            shutil.copytree(src / name, dest / name, ignore=shutil.ignore_patterns("tmp"))
        else:
            shutil.copy2(src / name, dest / name)


def _compile(root: Path, variant: str, pybind_dir: str | None) -> None:
    log_file = root / "build.log"
    steps: list[tuple[str, list[str]]] = []
    if variant in _PYTHON_TRACK:
        python = sys.executable
        # What the kit's python/set_track.bash does, in Python: the script expands its own
        # folder unquoted (rm -rf $PYTHON_PATH"/tmp"/*), so a cache path with a space
        # would delete what stands before the space.
        set_track(root, _PYTHON_TRACK[variant])
        steps.append(
            ("cmake", [
                "cmake", "-B", "build", "./", "-DPYTHON=true", "-DCMAKE_BUILD_TYPE=Release",
                f"-Dpybind11_DIR={pybind_dir}", f"-DPython_EXECUTABLE={python}",
                f"-DPYTHON_EXECUTABLE={python}",
                f"-DPython_ROOT_DIR={sysconfig.get_config_var('prefix')}",
            ])
        )  # fmt: skip
    else:
        steps.append(
            (
                "cmake",
                ["cmake", "-B", "build", "./", "-DPYTHON=false", "-DCMAKE_BUILD_TYPE=Release"],
            )
        )
    steps.append(("make", ["make", "-C", "build", f"-j{os.cpu_count() or 1}"]))
    with open(log_file, "w", encoding="utf-8") as fh:
        for name, command in steps:
            fh.write(f"$ {' '.join(command)}\n")
            fh.flush()
            done = subprocess.run(command, cwd=root, stdout=fh, stderr=subprocess.STDOUT)
            if done.returncode != 0:
                kept = root.parent / f"{root.name.strip('.')}.failed.log"
                shutil.copy2(log_file, kept)
                raise StartKitError(
                    f"start kit build failed at {name} (exit {done.returncode}): "
                    f"{_last_error(kept)} (log: {kept})"
                )


#: ``python/set_track.bash``'s tracks: the folders whose files make ``python/tmp``.
_TRACKS = {
    "combined": ("common", "user_planner", "user_scheduler"),
    "planner": ("common", "user_planner", "default_scheduler"),
    "scheduler": ("common", "default_planner", "user_scheduler"),
}


def set_track(root: Path, track: str) -> None:
    """Fill ``root/python/tmp`` with a track's Python sources, as the kit's
    ``set_track.bash TRACK`` does (its ``cp -r DIR/* tmp``: entries not starting with a
    dot, later folders replacing earlier ones), with no shell and any path.

    Raises:
        StartKitError: An unknown track, or a source folder missing from the kit.
    """
    if track not in _TRACKS:
        raise StartKitError(f"unknown start kit track {track!r}; valid: {', '.join(_TRACKS)}")
    python = root / "python"
    tmp = python / "tmp"
    shutil.rmtree(tmp, ignore_errors=True)
    tmp.mkdir(parents=True)
    for name in _TRACKS[track]:
        src = python / name
        if not src.is_dir():
            raise StartKitError(f"the start kit has no python/{name} folder ({src})")
        for entry in sorted(src.iterdir()):
            if entry.name.startswith("."):
                continue  # the shell's * leaves hidden entries out
            if entry.is_dir():
                shutil.copytree(entry, tmp / entry.name, dirs_exist_ok=True)
            else:
                shutil.copy2(entry, tmp / entry.name)


def _last_error(log_file: Path) -> str:
    lines = [ln.strip() for ln in log_file.read_text(errors="replace").splitlines() if ln.strip()]
    errors = [ln for ln in lines if "error" in ln.lower()]
    return (errors or lines or ["no output"])[0][:200]


@contextmanager
def _locked(path: Path) -> Iterator[None]:
    with open(path, "w") as fh:
        fcntl.flock(fh, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(fh, fcntl.LOCK_UN)


def main(argv: list[str] | None = None) -> None:
    """``python -m rtaw_marl.integrations.lorr.kit``: build the Python variants if the
    start kit is there (``make test`` runs this before the suite), else say so and pass.
    ``--missing`` prints the missing Debian packages, one line, for ``make lorr-kit``
    (none when there is no kit to build)."""
    args = sys.argv[1:] if argv is None else argv
    if args == ["--missing"]:
        try:
            kit_source()
        except StartKitError:
            print()  # no kit here: nothing to build, so nothing to install
            return
        print(" ".join(missing_packages()))
        return
    if args:
        print(f"error: unknown arguments {' '.join(args)}; valid: --missing", file=sys.stderr)
        sys.exit(2)
    try:
        kit_source()
    except StartKitError as exc:
        print(f"skipped: {exc}; the LoRR start kit tests will skip", file=sys.stderr)
        return
    try:
        for variant in ("python", "planner"):
            build_kit(variant)
    except StartKitError as exc:
        print(f"error: {exc}", file=sys.stderr)
        sys.exit(2)


if __name__ == "__main__":
    main()
