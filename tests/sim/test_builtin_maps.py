"""The maps shipped in ``rtaw_marl/maps/`` and the ``builtin:NAME`` path syntax: the
files are upstream's bytes with their licenses, the wheel carries them, and every reader
(layouts, LoRR problems, the env, rtaw-eval, rtaw-lorr, the evaluation journal) resolves
the syntax through the one resolver."""

from __future__ import annotations

import dataclasses
import glob
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from rtaw_marl.errors import ConfigError, LayoutError
from rtaw_marl.sim.layout import load_layout
from rtaw_marl.sim.maps import BUILTIN, MAPS, MAPS_DIR, map_path, resolve_path

pytestmark = pytest.mark.unit

ROOT = Path(__file__).resolve().parents[2]
SHARED = ROOT.parent / "shared"
_LORR_RANDOM = "lorr/start-kit-v2.1.2/example_problems/random.domain"

#: Every shipped file -> its source under ../shared (the README is ours).
_RTAW = ("open_64", "usc_64", "tight_64", "tight_2_64", "compact_64", "compact_2_64")
SOURCES = {
    **{f"rtaw/{n}.cfg": f"maps/rtaw/{n}.cfg" for n in _RTAW},
    "rtaw/LICENSE": "maps/rtaw/LICENSE",
    "movingai/warehouse-10-20-10-2-1.map": "maps/movingai/warehouse-10-20-10-2-1.map",
    "movingai/LICENCE.txt": "maps/movingai/LICENCE.txt",
    "lorr/random_32_32_20_100.json": f"{_LORR_RANDOM}/random_32_32_20_100.json",
    "lorr/maps/random-32-32-20.map": f"{_LORR_RANDOM}/maps/random-32-32-20.map",
    "lorr/agents/random_32_32_20_100.agents": f"{_LORR_RANDOM}/agents/random_32_32_20_100.agents",
    "lorr/tasks/random_32_32_20.tasks": f"{_LORR_RANDOM}/tasks/random_32_32_20.tasks",
    "lorr/LICENSE": "maps/lorr/LICENSE",
}

#: Size and free cells of each shipped map (../shared/maps/README.md; the LoRR map counted
#: here: 1024 cells, 205 '@').
SIZES = {
    "open_64.cfg": (64, 64, 3536),
    "usc_64.cfg": (64, 64, 3536),
    "tight_64.cfg": (64, 64, 3068),
    "tight_2_64.cfg": (64, 64, 3068),
    "compact_64.cfg": (64, 64, 3296),
    "compact_2_64.cfg": (64, 64, 3336),
    "warehouse-10-20-10-2-1.map": (161, 63, 5699),
    "random-32-32-20.map": (32, 32, 819),
}

PROBLEM = "random_32_32_20_100.json"


def _shipped() -> set[str]:
    return {p.relative_to(MAPS_DIR).as_posix() for p in MAPS_DIR.rglob("*") if p.is_file()}


# ----------------------------------------------------------------- the files


def test_the_folder_holds_exactly_the_listed_files() -> None:
    """Nothing stray is shipped (a cache, an edited copy) and nothing listed is missing."""
    assert _shipped() == {*SOURCES, "README.md"}


@pytest.mark.parametrize("shipped", sorted(SOURCES))
def test_shipped_file_is_byte_identical_to_its_source(shipped: str) -> None:
    source = SHARED / SOURCES[shipped]
    if not source.is_file():
        pytest.skip(f"{source} not present (no ../shared beside the repository)")
    assert (MAPS_DIR / shipped).read_bytes() == source.read_bytes()


@pytest.mark.parametrize(
    ("folder", "license_file", "holder"),
    [
        ("rtaw", "LICENSE", "Aakriti05"),
        ("movingai", "LICENCE.txt", "AIST"),
        ("lorr", "LICENSE", "The League of Robot Runners"),
    ],
)
def test_every_shipped_folder_has_its_license(folder: str, license_file: str, holder: str) -> None:
    """Each source folder carries its repository's MIT text, naming the copyright holder."""
    text = (MAPS_DIR / folder / license_file).read_text()
    assert "Permission is hereby granted, free of charge" in text
    assert holder in text
    assert {f.split("/")[0] for f in SOURCES if f.startswith(f"{folder}/")} == {folder}


def test_readme_names_every_shipped_file_and_its_source() -> None:
    readme = (MAPS_DIR / "README.md").read_text()
    for shipped in SOURCES:
        if "LICEN" not in shipped:
            assert shipped in readme
    for commit in (
        "326f2651e186299d77aafc8ba427c7bbe9f2063a",
        "1a269b7addc1edc4f1f56b194d307190f5491943",
        "72b409f52f4ca76a29b9dce849ed5f624dae0293",
    ):
        assert commit in readme


def test_package_data_puts_every_shipped_file_in_the_wheel() -> None:
    """pyproject's package-data globs, expanded as setuptools does (``glob(recursive=True)``
    relative to the package folder), match every shipped file."""
    tomllib = pytest.importorskip("tomllib")
    setuptools = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    assert "rtaw_marl*" in setuptools["packages"]["find"]["include"]
    package = ROOT / "rtaw_marl"
    matched = {
        Path(hit).relative_to(package).as_posix()
        for pattern in setuptools["package-data"]["rtaw_marl"]
        for hit in glob.glob(str(package / pattern), recursive=True)
        if Path(hit).is_file()
    }
    missing = sorted(f"maps/{f}" for f in _shipped() if f"maps/{f}" not in matched)
    assert not missing, missing


# ----------------------------------------------------------------- names and paths


def test_every_name_is_a_shipped_file() -> None:
    assert set(MAPS) == {*SIZES, PROBLEM}
    for name in MAPS:
        assert map_path(name).is_file()
        assert map_path(name).name == name


@pytest.mark.parametrize("name", ["usc64.cfg", "", "rtaw/usc_64.cfg", "random_32_32_20.tasks"])
def test_an_unknown_name_is_one_error_listing_the_names(name: str) -> None:
    with pytest.raises(ConfigError) as info:
        map_path(name)
    message = str(info.value)
    assert "\n" not in message
    assert message.startswith(f"unknown builtin map {name!r}; available: ")
    assert all(n in message for n in MAPS)
    # The same error through the syntax, from every reader.
    with pytest.raises(ConfigError, match="unknown builtin map"):
        load_layout(f"{BUILTIN}{name}")


def test_a_wrong_name_gets_a_suggestion() -> None:
    with pytest.raises(ConfigError, match=r"did you mean 'usc_64\.cfg'"):
        resolve_path("builtin:usc64.cfg")


def test_ordinary_paths_are_left_alone(tmp_path: Path) -> None:
    """Only a ``str`` starting with ``builtin:`` is resolved; nothing falls back to a
    shipped map, and a missing file is still the reader's own error."""
    assert resolve_path("maps/usc_64.cfg") == Path("maps/usc_64.cfg")
    assert resolve_path(tmp_path / "x.cfg") == tmp_path / "x.cfg"
    assert resolve_path(Path("builtin:usc_64.cfg")) == Path("builtin:usc_64.cfg")
    assert resolve_path("./builtin:usc_64.cfg") == Path("./builtin:usc_64.cfg")
    with pytest.raises(LayoutError, match=r"layout file not found: usc_64\.cfg"):
        load_layout("usc_64.cfg")


def test_light_import() -> None:
    """The resolver is stdlib only: importing it loads no numpy."""
    code = "import sys, rtaw_marl.sim.maps; print('numpy' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


# ----------------------------------------------------------------- layouts


@pytest.mark.parametrize("name", sorted(SIZES))
def test_builtin_layout_loads_with_its_size(name: str) -> None:
    from rtaw_marl.sim.options import layout_option

    width, height, free = SIZES[name]
    layout = load_layout(f"builtin:{name}")
    assert (layout.width, layout.height, len(layout.free_cells)) == (width, height, free)
    assert layout.name == Path(name).stem
    # The same map through every layout spelling of the options.
    for spec in (f"builtin:{name}", {"name": "file", "path": f"builtin:{name}"}):
        assert np.array_equal(layout_option(spec).build().obstacles, layout.obstacles)
    shelves = layout_option({"name": "shelves", "path": f"builtin:{name}"}).build()
    assert np.array_equal(shelves.obstacles, layout.obstacles)


def test_layout_option_sends_a_builtin_name_without_a_dot_to_the_resolver() -> None:
    """``builtin:usc`` is a (wrong) map name, not an unknown layout option."""
    from rtaw_marl.sim.options import layout_option

    with pytest.raises(ConfigError, match=r"unknown builtin map 'usc'; available: "):
        layout_option("builtin:usc").build()


def test_env_runs_an_episode_on_a_builtin_layout() -> None:
    """``warehouse_v1.env(layout="builtin:...")``: the map's grid, an episode to the end."""
    from rtaw_marl import warehouse_v1
    from rtaw_marl.policies import make_baseline

    for layout in ("builtin:usc_64.cfg", {"name": "file", "path": "builtin:tight_64.cfg"}):
        env = warehouse_v1.env(layout=layout, num_robots=3, num_tasks=12, queue_len=4)
        env.reset(seed=0)
        rule = make_baseline("mpdm", env=env)
        for _ in env.agent_iter():
            obs, _, term, trunc, _ = env.last()
            env.step(None if term or trunc else rule.act(obs))
        sim = env.unwrapped.sim
        assert (sim.layout.width, sim.layout.height) == (64, 64)
        assert sim.metrics().tasks_finished == 12
        env.close()


@pytest.mark.integration  # a CLI run (Hydra composition)
def test_rtaw_eval_runs_on_a_builtin_layout(cli, tmp_path: Path) -> None:
    out = tmp_path / "r.json"
    result = cli("eval", "layout.path=builtin:usc_64.cfg", "policy=mpdm", "seeds=[0,1]",
                 "sim.num_tasks=20", "progress=false", f"output={out}")  # fmt: skip
    assert result.code == 0, result.err
    assert "layout usc_64: 64x64, 3536 free cells" in result.out
    data = json.loads(out.read_text())
    assert data["config"]["layout"]["path"] == "builtin:usc_64.cfg"
    assert len(data["policies"]["mpdm"]["ttd"]) == 2


@pytest.mark.integration  # a CLI run (Hydra composition)
def test_rtaw_eval_names_the_valid_maps_for_a_wrong_one(cli) -> None:
    result = cli("eval", "layout.path=builtin:usc.cfg", "policy=mpdm", "progress=false")
    assert result.code == 2
    assert result.err.strip().splitlines() == [
        line for line in result.err.strip().splitlines() if line.startswith("error:")
    ]
    assert "unknown builtin map 'usc.cfg'; available: compact_2_64.cfg" in result.err
    assert "Traceback" not in result.err


def test_the_journal_digests_the_shipped_file() -> None:
    """rtaw-eval's resume matches settings by file contents: a builtin path is digested
    as the file it names (so it matches the same map given by its real path)."""
    from rtaw_marl.evaluation.journal import file_digest, with_file_digests

    by_name = with_file_digests({"layout": {"path": "builtin:usc_64.cfg"}})
    by_path = with_file_digests({"layout": {"path": str(map_path("usc_64.cfg"))}})
    assert by_name == by_path == {"layout": {"path": file_digest(map_path("usc_64.cfg"))}}


# ----------------------------------------------------------------- the LoRR problem


def test_lorr_problem_loads_through_builtin() -> None:
    from rtaw_marl.sim.lorr import read_problem
    from rtaw_marl.sim.options import LoRRLayoutConfig, LoRRTasksConfig

    problem = read_problem(f"builtin:{PROBLEM}")
    assert problem.path == map_path(PROBLEM)
    assert problem.map_path == (MAPS_DIR / "lorr" / "maps" / "random-32-32-20.map").resolve()
    assert (problem.team_size, problem.reveal) == (100, 1.5)
    layout = LoRRLayoutConfig(problem=f"builtin:{PROBLEM}").build()
    assert (layout.width, layout.height, len(layout.free_cells)) == (32, 32, 819)
    stream = LoRRTasksConfig(problem=f"builtin:{PROBLEM}").build()
    assert stream.tasks.shape == (100_000, 4)
    assert stream.agents.shape == (100, 2)


def test_lorr_scenario_plays_from_builtin() -> None:
    from rtaw_marl.evaluation.evaluate import run_episode
    from rtaw_marl.policies import make_baseline
    from rtaw_marl.scenarios import lorr_scenario
    from rtaw_marl.sim.builder import build_sim

    scenario = lorr_scenario(f"builtin:{PROBLEM}", num_robots=10, horizon=30)
    assert scenario.name == "lorr_random_32_32_20_100"
    sim = build_sim(scenario.spec())
    run_episode(sim, make_baseline("mpdm"), seed=0)
    assert sim.metrics().tasks_finished > 0


@pytest.mark.integration  # a CLI run (Hydra composition)
def test_rtaw_eval_runs_a_builtin_lorr_problem(cli, tmp_path: Path) -> None:
    """``scenario=lorr tasks.problem=builtin:...``: the Hydra resolvers that derive the
    robots and the window read the shipped problem too."""
    out = tmp_path / "l.json"
    result = cli("eval", "scenario=lorr", f"tasks.problem=builtin:{PROBLEM}", "sim.horizon=20",
                 "sim.num_robots=10", "policy=mpdm", "seeds=[0]", "progress=false",
                 f"output={out}")  # fmt: skip
    assert result.code == 0, result.err
    assert "layout random-32-32-20: 32x32, 819 free cells" in result.out
    assert json.loads(out.read_text())["config"]["sim"]["queue_len"] == 15


@pytest.mark.integration  # a CLI run (Hydra composition)
def test_rtaw_lorr_resolves_a_builtin_problem(cli, tmp_path: Path, monkeypatch) -> None:
    """``rtaw-lorr problem=builtin:...`` hands LoRR's simulator and every scheduler the
    shipped JSON (the kit itself is faked: building it takes minutes)."""
    import rtaw_marl.cli.lorr as lorr_cli
    from rtaw_marl.integrations.lorr.kit import KitBuild
    from rtaw_marl.integrations.lorr.run import LoRRRun

    seen: list[tuple[Path, object]] = []

    def fake_run(build, problem, folder, spec, label, *rest) -> LoRRRun:
        seen.append((Path(problem), spec))
        return LoRRRun(label, 1, 10, 100, 0, 0, 0, 0.0, str(folder / "out.json"))

    monkeypatch.setattr(lorr_cli, "build_kit", lambda variant, *a: KitBuild(variant, tmp_path))
    monkeypatch.setattr(lorr_cli, "run_lifelong", fake_run)
    out = tmp_path / "results.json"
    result = cli("lorr", f"problem=builtin:{PROBLEM}", "policy=[lorr_default,mpdm]",
                 f"output={out}")  # fmt: skip
    assert result.code == 0, result.err
    assert [p for p, _ in seen] == [map_path(PROBLEM)] * 2
    specs = [spec for _, spec in seen if spec is not None]
    assert [dataclasses.asdict(s)["problem"] for s in specs] == [str(map_path(PROBLEM))]
    assert json.loads(out.read_text())["problem"] == str(map_path(PROBLEM))

    bad = cli("lorr", "problem=builtin:random.json", f"output={out}")
    assert bad.code == 2
    assert "unknown builtin map 'random.json'; available:" in bad.err
