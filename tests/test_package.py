"""The package's basics: licence, changelog, citation, one version, ``python -m rtaw_marl``,
and one clear error from a Python entry point whose extra is not installed."""

from __future__ import annotations

import ast
import importlib.metadata
import json
import pickle
import re
import subprocess
import sys
import textwrap
from pathlib import Path
from typing import Any

import pytest

import rtaw_marl
from rtaw_marl.errors import EXTRAS, MissingExtraError, extra_modules, missing_extra
from rtaw_marl.utils.commands import NEEDS, SUMMARIES
from tests.test_install_light import BLOCK

pytestmark = pytest.mark.unit

ROOT = Path(__file__).resolve().parents[1]
PAPER = (
    "RTAW: An Attention Inspired Reinforcement Learning Method for Multi-Robot Task "
    "Allocation in Warehouse Environments"
)
AUTHORS = [("Aakriti", "Agrawal"), ("Amrit Singh", "Bedi"), ("Dinesh", "Manocha")]


def _pyproject() -> dict[str, Any]:
    tomllib = pytest.importorskip("tomllib")
    return tomllib.loads((ROOT / "pyproject.toml").read_text())


def _python_m(*args: str, code: str | None = None) -> subprocess.CompletedProcess[str]:
    """``python -m rtaw_marl ARGS`` (or ``python -c CODE``) from the source tree."""
    argv = ["-c", code] if code is not None else ["-m", "rtaw_marl", *args]
    return subprocess.run(
        [sys.executable, *argv], cwd=ROOT, capture_output=True, text=True, timeout=60
    )


def test_license_is_mit() -> None:
    text = (ROOT / "LICENSE").read_text()
    assert text.startswith("MIT License\n")
    assert "Copyright (c) 2026 The rtaw_marl authors" in text
    assert "Permission is hereby granted, free of charge" in text
    assert 'THE SOFTWARE IS PROVIDED "AS IS", WITHOUT WARRANTY OF ANY KIND' in text
    assert _pyproject()["project"]["license"] == "MIT"


def test_changelog_has_unreleased_and_this_version() -> None:
    headings = re.findall(r"^## \[([^\]]+)\]", (ROOT / "CHANGELOG.md").read_text(), re.M)
    assert headings[0] == "Unreleased"
    assert rtaw_marl.__version__ in headings


def test_citation_names_the_paper_and_this_version() -> None:
    yaml = pytest.importorskip("yaml")
    cff = yaml.safe_load((ROOT / "CITATION.cff").read_text())
    assert cff["cff-version"] == "1.2.0"
    assert (cff["type"], cff["title"], cff["license"]) == ("software", "rtaw_marl", "MIT")
    assert cff["version"] == rtaw_marl.__version__
    paper = cff["preferred-citation"]
    assert paper["type"] == "conference-paper"
    assert paper["title"] == PAPER
    assert [(a["given-names"], a["family-names"]) for a in paper["authors"]] == AUTHORS
    assert paper["year"] == 2023
    assert "(ICRA)" in paper["conference"]["name"]


def test_the_version_is_written_once() -> None:
    """pyproject reads ``rtaw_marl.__version__``; the installed metadata agrees (a stale
    install fails here: reinstall with ``pip install -e .``)."""
    project = _pyproject()
    assert "version" not in project["project"]
    assert "version" in project["project"]["dynamic"]
    dynamic = project["tool"]["setuptools"]["dynamic"]["version"]
    assert dynamic == {"attr": "rtaw_marl.__version__"}
    assert importlib.metadata.version("rtaw_marl") == rtaw_marl.__version__


def test_console_scripts_are_the_command_table() -> None:
    """Each console script is ``rtaw-<command>`` -> ``rtaw_marl.cli:<command>_main`` for a
    command of the table, with an extra and a one-line summary; no command is left out."""
    scripts = _pyproject()["project"]["scripts"]
    assert scripts == {f"rtaw-{c}": f"rtaw_marl.cli:{c}_main" for c in NEEDS}
    assert set(SUMMARIES) == set(NEEDS)
    assert all(s and "\n" not in s for s in SUMMARIES.values())
    assert {extra for extra, _ in NEEDS.values()} <= set(EXTRAS)


def test_python_m_lists_every_console_script_with_its_extra() -> None:
    proc = _python_m()
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr == ""
    first = proc.stdout.splitlines()[0]
    assert first.startswith(f"rtaw_marl {rtaw_marl.__version__}: learned lifelong ")
    listed = dict(re.findall(r"^  (rtaw-[a-z]+) +([a-z]+) +\S", proc.stdout, re.M))
    scripts = _pyproject()["project"]["scripts"]
    assert set(listed) == set(scripts)
    for script, extra in listed.items():
        assert extra == NEEDS[script.removeprefix("rtaw-")][0], script
    assert "from rtaw_marl import warehouse_v1" in proc.stdout
    assert "docs/index.md" in proc.stdout


@pytest.mark.parametrize("flag", ["-h", "--help"])
def test_python_m_help_is_the_overview(flag: str) -> None:
    assert _python_m(flag).stdout == _python_m().stdout


def test_python_m_version_prints_the_version_alone() -> None:
    proc = _python_m("--version")
    assert (proc.returncode, proc.stdout, proc.stderr) == (0, f"{rtaw_marl.__version__}\n", "")


@pytest.mark.parametrize(
    ("args", "hint"),
    [
        (["--verison"], "did you mean '--version'?"),
        (["list"], "'list'"),
        (["--version", "--help"], "'--version --help'"),
    ],
)
def test_python_m_bad_argument_is_one_line_and_exit_2(args: list[str], hint: str) -> None:
    proc = _python_m(*args)
    assert proc.returncode == 2
    assert proc.stdout == ""
    assert proc.stderr.count("\n") == 1, proc.stderr
    assert proc.stderr.startswith("error: unknown argument ")
    assert "--version" in proc.stderr
    assert "--help" in proc.stderr
    assert hint in proc.stderr


def test_python_m_loads_nothing_heavy() -> None:
    """The overview answers on an install without extras: it imports none of them, nor
    the env's numpy and PettingZoo."""
    heavy = ("numpy", "pettingzoo", "gymnasium", *extra_modules("train"))
    code = (
        "import sys, rtaw_marl.__main__ as m; m.main([]);"
        f"print(sorted(n for n in {heavy!r} if n in sys.modules))"
    )
    proc = _python_m(code=code)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.splitlines()[-1] == "[]"


#: Makes the modules of ``BLOCKED`` unimportable (the env-only install's test has it).
_BLOCK = "import json\n" + BLOCK

PACKAGE = ROOT / "rtaw_marl"
#: Every module an extra installs (all extras).
EXTRA_IMPORTS = frozenset(m for extra in EXTRAS for m in EXTRAS[extra])
#: Parts guarded before their modules load: the console scripts' wrappers check a
#: command's extra before importing it, and importing a module of rtaw_marl.config runs
#: the package's guard (rtaw_marl/config/__init__.py) first.
GUARDED_ABOVE = ("cli/", "config/")


def _module_name(path: Path) -> str:
    parts = path.relative_to(ROOT).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _guard_extra(node: ast.Try) -> str | None:
    """The extra of a ``try`` whose handler raises ``missing_extra(exc, __name__, EXTRA)``."""
    for handler in node.handlers:
        for call in ast.walk(handler):
            if (
                isinstance(call, ast.Call)
                and getattr(call.func, "id", None) == "missing_extra"
                and isinstance(call.args[-1], ast.Constant)
            ):
                return call.args[-1].value
    return None


def _extra_imports(path: Path) -> tuple[list[int], set[str]]:
    """The lines of ``path``'s module-level imports of an extra's modules outside a
    ``missing_extra`` guard, and the extras its guards name. Imports in functions run
    on call (each has its own message), those under ``if TYPE_CHECKING`` never."""
    unguarded: list[int] = []
    extras: set[str] = set()

    def visit(body: list[ast.stmt], guarded: bool) -> None:
        for node in body:
            if isinstance(node, ast.Import | ast.ImportFrom):
                names = [a.name for a in node.names] if isinstance(node, ast.Import) else []
                if isinstance(node, ast.ImportFrom) and node.level == 0:
                    names = [node.module or ""]
                if {n.partition(".")[0] for n in names} & EXTRA_IMPORTS and not guarded:
                    unguarded.append(node.lineno)
            elif isinstance(node, ast.Try):
                extra = _guard_extra(node)
                if extra is not None:
                    extras.add(extra)
                visit(node.body, guarded or extra is not None)
                for part in (*(h.body for h in node.handlers), node.orelse, node.finalbody):
                    visit(part, guarded)
            elif isinstance(node, ast.If) and getattr(node.test, "id", "") != "TYPE_CHECKING":
                visit(node.body, guarded)
                visit(node.orelse, guarded)

    visit(ast.parse(path.read_text()).body, False)
    return unguarded, extras


def _modules() -> list[Path]:
    return [
        path
        for path in sorted(PACKAGE.rglob("*.py"))
        if not path.relative_to(PACKAGE).as_posix().startswith(GUARDED_ABOVE)
        or path == PACKAGE / "config" / "__init__.py"
    ]


def _guarded_modules() -> dict[str, str]:
    """Module -> the extra its import guard names."""
    guarded = {}
    for path in _modules():
        _, extras = _extra_imports(path)
        assert len(extras) <= 1, (path, extras)
        if extras:
            guarded[_module_name(path)] = extras.pop()
    return guarded


def test_every_module_imports_its_extra_behind_the_guard() -> None:
    """A module that imports torch, Hydra, ... when loaded does so inside ``try: ...
    except ModuleNotFoundError as exc: raise missing_extra(exc, __name__, EXTRA)``."""
    unguarded = {
        f"{path.relative_to(ROOT)}:{line}"
        for path in _modules()
        for line in _extra_imports(path)[0]
    }
    assert not unguarded, sorted(unguarded)
    guarded = _guarded_modules()
    assert guarded["rtaw_marl.models.checkpoint"] == "train"
    assert guarded["rtaw_marl.config"] == "cli"


_TRY_EACH = """
import rtaw_marl.policies  # the hand-written policies need no extra
from rtaw_marl.policies import make_baseline

make_baseline("mpdm")
outcomes = {}
for statement in STATEMENTS:
    try:
        exec(statement)
    except ImportError as exc:
        outcomes[statement] = {
            "type": f"{type(exc).__module__}.{type(exc).__qualname__}",
            "name": exc.name,
            "message": str(exc),
            "chained": exc.__cause__ is not None or not exc.__suppress_context__,
        }
    else:
        outcomes[statement] = None
print(json.dumps(outcomes))
"""


def test_python_entry_points_without_their_extra_raise_one_clear_error() -> None:
    """With every extra's modules unimportable, ``import rtaw_marl.policies`` and the
    hand-written rules work, and each entry point that needs an extra (every guarded
    module; ``load_policy`` and ``NetworkPolicy``) raises one :class:`MissingExtraError`,
    an ``ImportError``, naming it, the extra and its ``pip install``."""
    #: Statement -> (the name the error gives, the extra it names).
    entry_points = {
        "from rtaw_marl.policies import load_policy; load_policy('generalist_plus')": (
            "load_policy",
            "train",
        ),
        "from rtaw_marl.policies import NetworkPolicy": ("NetworkPolicy", "train"),
    }
    entry_points |= {f"import {m}": (m, extra) for m, extra in _guarded_modules().items()}
    assert "import rtaw_marl.training.ppo" in entry_points
    code = (
        f"BLOCKED = {tuple(sorted(EXTRA_IMPORTS))!r}\nSTATEMENTS = {list(entry_points)!r}\n"
        + textwrap.dedent(_BLOCK)
        + textwrap.dedent(_TRY_EACH)
    )
    proc = _python_m(code=code)
    assert proc.returncode == 0, proc.stderr
    outcomes = json.loads(proc.stdout.splitlines()[-1])
    wrong = {}
    for statement, (what, extra) in entry_points.items():
        got = outcomes[statement]
        ok = (
            got is not None
            and got["type"] == "rtaw_marl.errors.MissingExtraError"
            and got["name"] in extra_modules(extra)
            and got["message"].startswith(f"{what} needs the ")
            and got["message"].endswith(f"is not installed): pip install 'rtaw_marl[{extra}]'")
            and "\n" not in got["message"]
            and not got["chained"]
        )
        if not ok:
            wrong[statement] = got
    assert not wrong, wrong


def test_load_policy_without_torch_names_the_training_extra() -> None:
    """The newcomer's case: ``load_policy`` on an install without torch."""
    code = textwrap.dedent(_BLOCK) + textwrap.dedent("""
        from rtaw_marl.policies import load_policy
        load_policy("generalist_plus")
    """)
    proc = _python_m(code=f"BLOCKED = ('torch',)\n{code}")
    assert proc.returncode == 1
    last = proc.stderr.strip().splitlines()[-1]
    assert last == (
        "rtaw_marl.errors.MissingExtraError: load_policy needs the training extra "
        "('torch' is not installed): pip install 'rtaw_marl[train]'"
    )
    assert "During handling of the above exception" not in proc.stderr


def test_missing_extra_translates_only_the_extras_modules() -> None:
    torch_missing = ModuleNotFoundError("No module named 'torch.nn'", name="torch.nn")
    exc = missing_extra(torch_missing, "rtaw_marl.models.rtaw", "train")
    assert isinstance(exc, MissingExtraError)
    assert isinstance(exc, ImportError)
    assert (exc.name, exc.extra) == ("torch", "train")
    # The training extra installs the command-line one: tqdm missing -> install [train].
    tqdm_missing = ModuleNotFoundError("No module named 'tqdm'", name="tqdm")
    assert "rtaw_marl[train]" in str(missing_extra(tqdm_missing, "x", "train"))
    # A module no extra installs is a broken install: its own error is kept.
    other = ModuleNotFoundError("No module named 'sympy'", name="sympy")
    assert missing_extra(other, "x", "train") is other
    # The command-line extra does not install torch: not translated as if it did.
    assert missing_extra(torch_missing, "x", "cli") is torch_missing


def test_missing_extra_error_survives_pickling() -> None:
    """An evaluation worker's error reaches the parent process whole."""
    exc = missing_extra(ModuleNotFoundError(name="torch"), "load_policy", "train")
    back = pickle.loads(pickle.dumps(exc))
    assert type(back) is MissingExtraError
    assert (str(back), back.name, back.extra) == (str(exc), "torch", "train")
