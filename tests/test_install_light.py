"""The env alone: ``pip install rtaw_marl`` without extras needs only numpy, scipy, numba,
gymnasium and PettingZoo, and the commands whose extra is missing fail with one line."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

import rtaw_marl.cli

pytestmark = pytest.mark.system

ROOT = Path(__file__).resolve().parents[1]

#: Modules of the extras that the env path must not import.
HEAVY = ("torch", "torchrl", "tensordict", "hydra", "omegaconf", "tqdm", "matplotlib", "PIL")

EPISODE = """
import numpy as np
import rtaw_marl.sim, rtaw_marl.policies
from rtaw_marl.envs.pettingzoo import env as make_env
from rtaw_marl.policies import make_baseline

env = make_env(num_robots=4, num_tasks=30)
env.reset(seed=0)
rng = np.random.default_rng(0)
decisions = 0
for agent in env.agent_iter():
    obs, reward, terminated, truncated, info = env.last()
    if terminated or truncated:
        action = None
    else:
        action = int(rng.choice(np.flatnonzero(obs["action_mask"])))
        decisions += 1
    env.step(action)
assert decisions == 30, decisions
make_baseline("mpdm")
heavy = sorted(m for m in HEAVY if sys.modules.get(m) is not None)
print("loaded:", heavy)
assert not heavy, heavy
print("episode ok")
"""


def _clean_env() -> dict[str, str]:
    """The environment without anything that would put another tree on ``sys.path``."""
    drop = {"PYTHONPATH", "PYTHONHOME", "VIRTUAL_ENV", "PYTHONSTARTUP"}
    return {k: v for k, v in os.environ.items() if k not in drop}


def _script(body: str) -> str:
    return f"import sys\nHEAVY = {HEAVY!r}\n" + textwrap.dedent(body)


#: Makes the extras' modules look uninstalled (an import raises ModuleNotFoundError and
#: ``find_spec`` does too). Not ``sys.modules[name] = None``: scipy's array-API helpers
#: then fail on ``sys.modules["torch"].Tensor``, which no real install does.
BLOCK = """
import importlib.abc, sys

class _Block(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path=None, target=None):
        if name.partition(".")[0] in BLOCKED:
            raise ModuleNotFoundError(f"No module named {name!r}", name=name)
        return None

sys.meta_path.insert(0, _Block())
"""


def _blocked(blocked: tuple[str, ...], body: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    """Run ``body`` in a fresh interpreter (the source tree on its path) with ``blocked``
    unimportable."""
    code = f"BLOCKED = {blocked!r}\n" + BLOCK + _script(body)
    return subprocess.run(
        [sys.executable, "-c", code], cwd=cwd, capture_output=True, text=True,
        env={**_clean_env(), "PYTHONPATH": str(ROOT)}, timeout=300,
    )  # fmt: skip


def test_env_path_imports_with_the_training_stack_blocked(tmp_path: Path) -> None:
    """With torch, Hydra, tqdm and matplotlib unimportable, the env, the simulator and the
    hand-written policies still import and run an episode."""
    proc = _blocked(HEAVY, EPISODE, tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert "episode ok" in proc.stdout


@pytest.mark.parametrize(
    ("main", "blocked", "extra"),
    [
        ("train_main", "torch", "train"),
        ("train_main", "hydra", "train"),
        ("eval_main", "hydra", "cli"),
        ("eval_main", "tqdm", "cli"),
        ("render_main", "matplotlib", "cli"),
    ],
)
def test_command_without_its_extra_fails_with_one_line(
    main: str, blocked: str, extra: str, monkeypatch, capsys
) -> None:
    monkeypatch.setitem(sys.modules, blocked, None)
    monkeypatch.setattr(sys, "argv", ["rtaw-x"])
    with pytest.raises(SystemExit) as exc:
        getattr(rtaw_marl.cli, main)()
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1, err
    assert err.startswith("error: rtaw-")
    assert f"{blocked!r} is not installed" in err
    assert f"pip install 'rtaw_marl[{extra}]'" in err


def test_eval_of_a_trained_policy_without_torch_fails_with_one_line(tmp_path: Path) -> None:
    """Baselines need only the ``cli`` extra; ``policy=pretrained`` names the ``train`` extra."""
    body = """
    sys.argv = ["rtaw-eval", "scenario=poc", "policy=[pretrained]", "pretrained=shelves_astar_m10",
                "seeds=[0]", "progress=false"]
    import rtaw_marl.cli
    rtaw_marl.cli.eval_main()
    """
    proc = _blocked(("torch", "tensordict", "torchrl"), body, tmp_path)
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr.count("\n") == 1, proc.stderr
    assert "error: policy=pretrained needs the training extra ('torch' is not installed)" in (
        proc.stderr
    )
    assert "pip install 'rtaw_marl[train]'" in proc.stderr


def _pip_install(python: Path, *args: str) -> None:
    """Install into the venv of ``python`` with this interpreter's pip (``--python``):
    the fresh venv needs no pip of its own, and wheels come from pip's cache when there."""
    proc = subprocess.run(
        [sys.executable, "-m", "pip", "--python", str(python), "install", "--quiet",
         "--prefer-binary", *args],
        capture_output=True, text=True, timeout=900, env=_clean_env(),
    )  # fmt: skip
    assert proc.returncode == 0, proc.stdout + proc.stderr


@pytest.mark.slow
def test_env_only_install_in_a_fresh_venv(tmp_path: Path) -> None:
    """A venv with ``pip install rtaw_marl`` (no extras) and nothing else: no torch is
    installed, the env runs an episode, ``rtaw-train`` and ``rtaw-eval`` ask for their
    extras; with the ``cli`` extra, ``rtaw-eval`` runs the baselines, still without torch.

    Needs pip's cache or the package index (``make test`` installs from it anyway).
    """
    start = time.monotonic()
    wheels = tmp_path / "wheels"
    subprocess.run(
        [sys.executable, "-m", "pip", "wheel", "--quiet", "--no-deps", "--no-build-isolation",
         "--wheel-dir", str(wheels), str(ROOT)],
        check=True, capture_output=True, text=True, timeout=600,
    )  # fmt: skip
    (wheel,) = wheels.glob("rtaw_marl-*.whl")
    venv = tmp_path / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(venv)], check=True)
    bindir = venv / ("Scripts" if os.name == "nt" else "bin")
    python = bindir / "python"
    _pip_install(python, str(wheel))
    work = tmp_path / "work"  # not the source tree: the installed copy must run
    work.mkdir()

    def run(*cmd: str | Path, code: str | None = None) -> subprocess.CompletedProcess[str]:
        argv = [str(python), "-c", code] if code is not None else [str(c) for c in cmd]
        return subprocess.run(
            argv, cwd=work, capture_output=True, text=True, env=_clean_env(), timeout=600
        )

    probe = run(code=f"import importlib.util as u; print([m for m in {HEAVY!r} if u.find_spec(m)])")
    assert probe.returncode == 0, probe.stderr
    assert probe.stdout.strip() == "[]", f"an extra got installed: {probe.stdout}"

    episode = run(code=_script(EPISODE))
    assert episode.returncode == 0, episode.stderr
    assert "episode ok" in episode.stdout
    where = run(code="import rtaw_marl; print(rtaw_marl.__file__)")
    assert where.stdout.startswith(str(venv)), where.stdout
    # The tutorial's first block, verbatim: a shipped map from the installed wheel, no
    # source tree and no ../shared.
    tutorial = (ROOT / "docs" / "tutorial.md").read_text().split("```python\n")[1]
    first = run(code=tutorial.split("```")[0])
    assert first.returncode == 0, first.stderr
    assert "random policy: TTD" in first.stdout

    for tool, extra in (("rtaw-train", "train"), ("rtaw-eval", "cli"), ("rtaw-render", "cli")):
        proc = run(bindir / tool)
        assert proc.returncode == 2, (tool, proc.stdout, proc.stderr)
        assert proc.stderr.count("\n") == 1, proc.stderr
        assert proc.stderr.startswith(f"error: {tool} needs the "), proc.stderr
        assert f"pip install 'rtaw_marl[{extra}]'" in proc.stderr

    # The cli extra: rtaw-eval with hand-written policies, and no torch anywhere.
    _pip_install(python, f"{wheel}[cli]")
    proc = run(bindir / "rtaw-eval", "scenario=poc", "policy=[mpdm,rbts]", "seeds=[0]",
               "progress=false")  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    assert "22.74" in proc.stdout
    assert "18.46" in proc.stdout
    # A shipped map and the user's own rule, from the installed copy.
    (work / "my_rules.py").write_text(
        "import numpy as np\n\n\ndef first(sim):\n"
        "    return int(np.flatnonzero(sim.queue_mask)[0])\n"
    )
    proc = run(bindir / "rtaw-eval", "layout=file", "layout.path=builtin:usc_64.cfg",
               "sim.num_tasks=20", "policy=[mpdm,my_rules:first]", "seeds=[0]",
               "progress=false", "output=r.json")  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    assert "| first |" in proc.stdout
    assert (work / "r.csv").is_file()
    proc = run(bindir / "rtaw-eval", "scenario=poc", "policy=[pretrained]",
               "pretrained=shelves_astar_m10", "seeds=[0]", "progress=false")  # fmt: skip
    assert proc.returncode == 2, proc.stderr
    assert "pip install 'rtaw_marl[train]'" in proc.stderr
    assert proc.stderr.count("\n") == 1, proc.stderr
    proc = run(bindir / "rtaw-train")
    assert proc.returncode == 2
    assert "'torch' is not installed" in proc.stderr
    print(f"env-only install test: {time.monotonic() - start:.0f} s")
