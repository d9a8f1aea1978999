"""The layers: data flows one way, no import circles, light packages stay light."""

from __future__ import annotations

import ast
import re
import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.unit

PACKAGE = Path(__file__).resolve().parents[1] / "rtaw_marl"

#: Layer of each part of the package; a module may import only its own layer or lower ones.
LAYERS = {
    "rtaw_marl": 0,
    "rtaw_marl.errors": 0,
    "rtaw_marl.utils": 0,
    "rtaw_marl.sim": 1,
    # Named settings over the simulator's options: below every adapter.
    "rtaw_marl.scenarios": 1.5,
    # The decision model (what a freed robot observes): below the adapters, the models
    # and the policies, which all read it; NumPy and Numba only.
    "rtaw_marl.decision": 1.7,
    "rtaw_marl.envs": 2,
    "rtaw_marl.warehouse_v1": 2,
    "rtaw_marl.models": 3,
    "rtaw_marl.policies": 4,
    "rtaw_marl.evaluation": 5,
    "rtaw_marl.viz": 5,
    "rtaw_marl.training": 6,
    # Adapters to other libraries (BenchMARL): above the envs, beside training.
    "rtaw_marl.integrations": 6,
    "rtaw_marl.config": 7,
    "rtaw_marl.cli": 8,
}


def _module_name(path: Path) -> str:
    parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _imports() -> dict[str, set[str]]:
    """Every rtaw_marl module -> the rtaw_marl modules it imports (function bodies too)."""
    graph: dict[str, set[str]] = {}
    for path in PACKAGE.rglob("*.py"):
        name = _module_name(path)
        targets: set[str] = set()
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Import):
                targets |= {a.name for a in node.names if a.name.startswith("rtaw_marl")}
            elif isinstance(node, ast.ImportFrom) and (node.module or "").startswith("rtaw_marl"):
                targets.add(node.module)
        graph[name] = targets
    return graph


def _layer(module: str) -> tuple[str, int]:
    best = max((k for k in LAYERS if module == k or module.startswith(k + ".")), key=len)
    return best, LAYERS[best]


def test_every_import_goes_down_the_layers() -> None:
    upward = []
    for module, targets in _imports().items():
        own, rank = _layer(module)
        for target in targets:
            other, other_rank = _layer(target)
            if other_rank > rank:
                upward.append(f"{module} ({own}) imports {target} ({other})")
    assert not upward, "\n".join(sorted(upward))


def test_no_import_cycles_between_modules() -> None:
    graph = _imports()
    names = set(graph)

    def resolve(target: str) -> str | None:
        # "from rtaw_marl.sim import core" names a package; count it as the package module.
        while target and target not in names:
            target = target.rpartition(".")[0]
        return target or None

    edges = {m: {t for t in map(resolve, ts) if t and t != m} for m, ts in graph.items()}
    # A package's __init__ importing its own submodules is not a cycle of the layers.
    edges = {m: {t for t in ts if not t.startswith(m + ".")} for m, ts in edges.items()}
    state: dict[str, int] = {}
    cycles: list[list[str]] = []

    def visit(node: str, stack: list[str]) -> None:
        state[node] = 1
        for nxt in sorted(edges[node]):
            if state.get(nxt) == 1:
                cycles.append([*stack[stack.index(nxt) :], nxt])
            elif nxt not in state:
                visit(nxt, [*stack, nxt])
        state[node] = 2

    for node in sorted(edges):
        if node not in state:
            visit(node, [node])
    assert not cycles, cycles


BENCHMARKS = PACKAGE.parent / "benchmarks"


def _imported_names(path: Path) -> list[tuple[str, str | None]]:
    """``(module, name)`` for every import in ``path`` (``name`` None for ``import m``)."""
    found: list[tuple[str, str | None]] = []
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            found += [(a.name, None) for a in node.names]
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            found += [(node.module, a.name) for a in node.names]
    return found


def test_the_package_never_imports_the_benchmarks_project() -> None:
    """benchmarks/ sits beside the package and uses it; the package knows nothing of it
    (and writes no docs page: the doc generators live there)."""
    upward = [
        f"{path.relative_to(PACKAGE.parent)} imports {module}"
        for path in PACKAGE.rglob("*.py")
        for module, _ in _imported_names(path)
        if module == "benchmarks" or module.startswith("benchmarks.")
    ]
    assert not upward, upward


def test_the_benchmarks_project_uses_only_public_names_of_the_package() -> None:
    """Every name benchmarks/ takes from rtaw_marl is public: no ``_private`` module or
    name, so the package can change its insides without breaking the results pages."""
    private = [
        f"{path.relative_to(PACKAGE.parent)}: {module}.{name or ''}"
        for path in BENCHMARKS.rglob("*.py")
        for module, name in _imported_names(path)
        if module.startswith("rtaw_marl")
        and (any(part.startswith("_") for part in module.split(".")) or (name or "x")[0] == "_")
    ]
    assert not private, private
    assert list(BENCHMARKS.glob("*.py")), "the benchmarks project is where the scripts live"


#: Modules installed only by the ``cli`` and ``train`` extras (pyproject.toml).
EXTRAS = ("torch", "torchrl", "tensordict", "hydra", "omegaconf", "tqdm", "matplotlib", "PIL")

#: What ``pip install rtaw_marl`` (no extras) installs: import name -> distribution.
BASE_DEPENDENCIES = {
    "numpy": "numpy",
    "scipy": "scipy",
    "numba": "numba",
    "gymnasium": "gymnasium",
    "pettingzoo": "pettingzoo",
}

#: The parts of the package that ``pip install rtaw_marl`` must run: the env, the simulator
#: and the hand-written policies (everything else needs an extra).
ENV_PATH = (
    "__init__.py", "errors.py", "warehouse_v*.py", "utils", "sim", "decision", "envs", "policies",
)  # fmt: skip
NEEDS_EXTRA = (
    "envs/torchrl.py", "envs/torchrl_wrapper.py", "envs/mixed.py", "policies/network.py",
    "policies/export.py", "policies/export_check.py", "policies/search_policy.py",
    "policies/matched.py",
)  # fmt: skip


def _env_path_files() -> list[Path]:
    files: list[Path] = []
    for pattern in ENV_PATH:
        for path in sorted(PACKAGE.glob(pattern)):
            files += sorted(path.rglob("*.py")) if path.is_dir() else [path]
    return [f for f in files if f.relative_to(PACKAGE).as_posix() not in NEEDS_EXTRA]


def _third_party(path: Path) -> set[str]:
    """Top-level names of the non-stdlib, non-rtaw_marl modules ``path`` imports anywhere."""
    names: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            names |= {a.name.partition(".")[0] for a in node.names}
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            names.add(node.module.partition(".")[0])
    return {n for n in names if n not in sys.stdlib_module_names and n != "rtaw_marl"}


def test_env_path_imports_only_the_base_dependencies() -> None:
    """Function bodies too: a lazy ``import torch`` in the env would break an env-only
    install as surely as a top-level one."""
    files = _env_path_files()
    assert PACKAGE / "envs" / "pettingzoo.py" in files
    stray = {
        f"{f.relative_to(PACKAGE)}: {name}"
        for f in files
        for name in _third_party(f) - set(BASE_DEPENDENCIES)
    }
    assert not stray, sorted(stray)


def test_base_dependencies_are_ranges_of_exactly_the_env_needs() -> None:
    tomllib = pytest.importorskip("tomllib")
    project = tomllib.loads((PACKAGE.parent / "pyproject.toml").read_text())["project"]
    requirements = project["dependencies"]
    names = {re.split(r"[<>=!~\[; ]", r, maxsplit=1)[0].lower() for r in requirements}
    assert names == set(BASE_DEPENDENCIES.values())
    assert not [r for r in requirements if "==" in r], "exact pins belong in the extras"
    train = " ".join(project["optional-dependencies"]["train"])
    assert all(m in train for m in ("torch", "tensordict", "torchrl", "rtaw_marl[cli]"))
    assert "rtaw_marl[train]" in project["optional-dependencies"]["dev"]


@pytest.mark.parametrize(
    ("module", "absent"),
    [
        ("rtaw_marl", ("torch", "pettingzoo", "hydra")),
        ("rtaw_marl.sim", ("torch", "pettingzoo", "hydra")),
        ("rtaw_marl.sim.builder", ("torch", "pettingzoo", "hydra", "omegaconf")),
        ("rtaw_marl.sim.mapf", ("torch", "pettingzoo", "hydra")),
        ("rtaw_marl.decision", ("torch", "pettingzoo", "gymnasium", "hydra")),
        ("rtaw_marl.envs.pettingzoo", EXTRAS),
        ("rtaw_marl.policies", EXTRAS),
        ("rtaw_marl.cli", (*EXTRAS, "pettingzoo", "numpy")),
        ("rtaw_marl.evaluation", ("torch", "torchrl", "tensordict", "hydra")),
        ("rtaw_marl.config", ("torch", "torchrl")),
    ],
)
def test_light_imports_stay_light(module: str, absent: tuple[str, ...]) -> None:
    """Importing the simulator loads no torch; the env and the hand-written policies load
    nothing of the extras; configs no torch; the console-script wrappers only the stdlib."""
    code = f"import sys, {module}; print(sorted(m for m in {absent!r} if m in sys.modules))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def test_every_path_named_in_the_architecture_page_exists() -> None:
    """docs/architecture.md names modules and folders (``sim/distances.py``,
    ``sim/mapf/``, ``tests/...``; in a table row, relative to the row's package): each
    exists."""
    page = (PACKAGE.parent / "docs" / "architecture.md").read_text()
    code = re.compile(r"`([\w.-]+(?:/[\w.-]*)*(?:\.py|/))(?::\w+)?`")
    missing, seen = [], 0
    for line in page.splitlines():
        row = re.match(r"\| [\d.]+ \| `([\w/]+)/`", line)
        base = PACKAGE / row.group(1) if row and row.group(1) != "rtaw_marl" else PACKAGE
        for name in code.findall(line):
            seen += 1
            places = [PACKAGE / name, PACKAGE.parent / name, base / name]
            if not any(p.exists() for p in places):
                missing.append(name)
    assert seen > 40
    assert not missing, missing
