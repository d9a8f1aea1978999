"""rtaw-eval: composition of every config option, results files, errors, sweeps."""

from __future__ import annotations

import json
import math
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from hydra.core.override_parser.overrides_parser import OverridesParser
from omegaconf import DictConfig
from scipy import stats as scipy_stats

from rtaw_marl.cli.common import typed
from rtaw_marl.cli.eval import run
from rtaw_marl.config import compose, group_options
from rtaw_marl.scenarios import ROWS
from rtaw_marl.sim.builder import build_sim

pytestmark = pytest.mark.integration

GROUPS = ("sim", "layout", "navigator", "tasks", "scenario", "row", "experiment")
GLOBAL_GROUPS = ("scenario", "row", "experiment")  # packaged at the top level
RTAW_EVAL = Path(sys.executable).with_name("rtaw-eval")


def _compose(overrides: list[str]) -> DictConfig:
    return compose(config_name="eval", overrides=overrides)


@pytest.mark.parametrize(
    ("group", "option"), [(g, o) for g in GROUPS for o in group_options(g)], ids=lambda v: str(v)
)
def test_every_option_composes_and_builds(group: str, option: str, tmp_path: Path) -> None:
    """Each option composes, and builds a simulator once its mandatory keys are set."""
    overrides = [f"{group}={option}"]
    if (group, option) == ("layout", "file"):
        layout = tmp_path / "grid.txt"
        layout.write_text("....\n.@..\n....\n")
        overrides += [f"layout.path={layout}", "sim.num_robots=2", "tasks=random"]
    if (group, option) == ("tasks", "file"):
        tasks = tmp_path / "tasks.csv"
        tasks.write_text("ox,oy,dx,dy\n" + "1,1,5,5\n" * 20)
        overrides += [f"tasks.path={tasks}", "sim.num_tasks=20"]
    if (group, option) == ("tasks", "poc"):
        overrides += ["sim.num_tasks=5", "layout=open"]
    if (group, option) == ("tasks", "stations"):
        overrides += ["layout=A"]
    if (group, option) == ("tasks", "two_task"):
        overrides += ["sim.queue_len=2", "layout=open"]
    if option == "lorr":
        problem = _tiny_lorr_problem(tmp_path)
        overrides += {
            "layout": [f"layout.problem={problem}", "tasks=random", "sim.num_robots=2"],
            "tasks": [f"tasks.problem={problem}", "layout=lorr", f"layout.problem={problem}",
                      "sim.num_robots=2", "sim.queue_len=3", "sim.refill=finish"],
            "scenario": [f"tasks.problem={problem}", "sim.horizon=20"],
        }[group]  # fmt: skip
    cfg = _compose(overrides)
    assert cfg[group if group not in GLOBAL_GROUPS else "sim"] is not None
    sim = build_sim(typed(cfg).sim_spec())
    sim.reset(0)
    assert not sim.done


def _tiny_lorr_problem(root: Path) -> Path:
    """A LoRR 2024 problem on a 6x3 grid: 2 robots, 3 tasks, a window of 1.5 x 2."""
    (root / "m.map").write_text("type octile\nheight 3\nwidth 6\nmap\n......\n.@..@.\n......\n")
    (root / "a.agents").write_text("# version for LoRR 2024\n2\n0\n17\n")
    (root / "t.tasks").write_text("# version for LoRR 2024\n3\n2,15\n12,5\n9,0\n")
    keys = {"mapFile": "m.map", "agentFile": "a.agents", "taskFile": "t.tasks",
            "teamSize": 2, "numTasksReveal": 1.5}  # fmt: skip
    (root / "p.json").write_text(json.dumps(keys))
    return root / "p.json"


def test_poc_golden_through_cli(tmp_path: Path) -> None:
    """The paper's proof of concept: MPDM 22.737 and RBTS 18.463, written to results.json."""
    out = tmp_path / "r.json"
    cfg = _compose(["scenario=poc", "policy=[mpdm,rbts]", "seeds=[0]", f"output={out}"])
    run(cfg)
    data = json.loads(out.read_text())
    assert data["policies"]["mpdm"]["ttd"][0] == pytest.approx(22.737, abs=0.01)
    assert data["policies"]["rbts"]["ttd"][0] == pytest.approx(18.463, abs=0.01)
    assert data["config"]["sim"]["num_robots"] == 2
    assert data["seeds"] == [0]


def test_cli_overrides_beat_scenario(tmp_path: Path) -> None:
    """Command-line values override a scenario's values and group choices."""
    cfg = _compose(["scenario=two_task", "sim.num_robots=3", "navigator=astar", "layout.width=12"])
    assert cfg.sim.num_robots == 3
    assert cfg.sim.episode_mode == "paper"
    assert cfg.navigator.name == "astar"
    assert (cfg.layout.name, cfg.layout.width, cfg.layout.height) == ("open", 12, 10)


def test_results_json_shape(tmp_path: Path) -> None:
    """results.json holds the config and one value per seed for every policy."""
    out = tmp_path / "sub" / "results.json"
    run(
        _compose(
            [
                "sim.num_tasks=40",
                "sim.num_robots=4",
                "policy=[mpdm,random]",
                "seeds=[0,1,2]",
                f"output={out}",
                "progress=false",
            ]
        )
    )
    data = json.loads(out.read_text())
    for name in ("mpdm", "random"):
        assert len(data["policies"][name]["ttd"]) == 3
        assert len(data["policies"][name]["makespan"]) == 3
    assert data["config"]["navigator"]["name"] == "astar"
    assert not list(out.parent.glob(".*tmp"))


def _strict_json(path: Path) -> dict:
    """``path`` parsed as strict JSON: NaN or Infinity fail the test."""

    def reject(constant: str) -> None:
        raise AssertionError(f"{path} holds {constant}, which is not JSON")

    return json.loads(path.read_text(), parse_constant=reject)


def _t_interval(baseline: list[float], other: list[float]) -> tuple[float, float, float]:
    """Mean and 95% paired t-interval of ``baseline - other``, straight from scipy."""
    d = np.asarray(baseline) - np.asarray(other)
    low, high = scipy_stats.t.interval(0.95, len(d) - 1, loc=d.mean(), scale=scipy_stats.sem(d))
    return float(d.mean()), float(low), float(high)


def test_results_json_comparisons_match_per_seed_values(tmp_path: Path, cli) -> None:
    """The comparisons block recomputed from the per-seed TTDs; no lower bound by default."""
    out = tmp_path / "r.json"
    result = cli(
        "eval",
        "scenario=poc",
        "policy=[mpdm,rbts,random]",
        "seeds=[0,1,2]",
        "progress=false",
        f"output={out}",
    )
    assert result.code == 0, result.err
    data = _strict_json(out)
    ttd = {name: data["policies"][name]["ttd"] for name in ("mpdm", "rbts", "random")}
    comparisons = data["comparisons"]
    assert comparisons["mpdm"] == {"vs": {}}
    for name in ("rbts", "random"):
        vs = comparisons[name]["vs"]
        assert set(vs) == {"mpdm"}
        mean, low, high = _t_interval(ttd["mpdm"], ttd[name])
        base = float(np.mean(ttd["mpdm"]))
        got = vs["mpdm"]
        assert got["n"] == 3
        assert got["baseline_mean"] == pytest.approx(base)
        assert got["other_mean"] == pytest.approx(np.mean(ttd[name]))
        assert got["mean_diff"] == pytest.approx(mean)
        if low == high or math.isnan(low):  # identical per-seed differences: zero width
            assert got["ci"] == pytest.approx([mean, mean])
        else:
            assert got["ci"] == pytest.approx([low, high])
        assert got["pct"] == pytest.approx(100 * mean / base)
        assert got["pct_ci"] == pytest.approx([100 * v / base for v in got["ci"]])
        assert got["significant"] == (got["ci"][0] > 0 or got["ci"][1] < 0)
    # The paper's proof of concept is deterministic for RBTS: 18.8% better on every seed.
    assert comparisons["rbts"]["vs"]["mpdm"]["pct"] == pytest.approx(18.8, abs=0.05)
    assert comparisons["rbts"]["vs"]["mpdm"]["significant"] is True
    assert "hindsight_share" not in comparisons["rbts"]
    # The lower bound is opt-in.
    assert (data["lower_bound"], data["lower_bound_time_s"]) == (None, None)
    assert "gap_pct" not in data["policies"]["mpdm"]
    assert "lower bound" not in result.out
    # The table: CI header, the paired cell, and the legend under it.
    assert "| TTD ± 95% CI |" in result.out
    assert "+18.8% [+18.8, +18.8]*" in result.out
    assert "* = interval excludes 0" in result.out


def test_compare_to_adds_a_second_baseline(tmp_path: Path, cli) -> None:
    out = tmp_path / "r.json"
    result = cli(
        "eval",
        "scenario=poc",
        "policy=[mpdm,rbts,random]",
        "seeds=[0,1]",
        "compare_to=rbts",
        "progress=false",
        f"output={out}",
    )
    assert result.code == 0, result.err
    data = _strict_json(out)
    assert data["config"]["compare_to"] == "rbts"
    comparisons = data["comparisons"]
    assert set(comparisons["mpdm"]["vs"]) == {"rbts"}
    assert set(comparisons["rbts"]["vs"]) == {"mpdm"}
    assert set(comparisons["random"]["vs"]) == {"mpdm", "rbts"}
    ttd = {name: data["policies"][name]["ttd"] for name in ("rbts", "random")}
    mean, _, _ = _t_interval(ttd["rbts"], ttd["random"])
    assert comparisons["random"]["vs"]["rbts"]["mean_diff"] == pytest.approx(mean)
    assert comparisons["mpdm"]["vs"]["rbts"]["pct"] == pytest.approx(
        -100 * (22.737 - 18.463) / 18.463, abs=0.05
    )
    header = result.out.splitlines()[1]
    assert "TTD vs MPDM" in header
    assert "TTD vs RBTS" in header


def test_compare_to_must_be_evaluated(cli) -> None:
    """A compare_to that is not among the policies: one line, exit 2, before any episode."""
    result = cli("eval", "scenario=poc", "policy=[mpdm,rbts]", "compare_to=random")
    assert result.code == 2
    assert result.err.strip() == (
        "error: compare_to=random is not an evaluated policy; evaluated: mpdm, rbts "
        "(or compare_to=best: the best rule here)"
    )
    assert "| policy" not in result.out


def test_one_seed_gives_null_intervals(tmp_path: Path, cli) -> None:
    out = tmp_path / "r.json"
    result = cli(
        "eval",
        "scenario=poc",
        "policy=[mpdm,rbts]",
        "seeds=[0]",
        "progress=false",
        f"output={out}",
    )
    assert result.code == 0, result.err
    vs = _strict_json(out)["comparisons"]["rbts"]["vs"]["mpdm"]
    assert (vs["ci"], vs["pct_ci"], vs["sd_diff"], vs["significant"]) == (None, None, None, False)
    assert "+18.8% [n/a]" in result.out


def test_lower_bound_on_request_is_timed(tmp_path: Path, cli) -> None:
    out = tmp_path / "r.json"
    result = cli(
        "eval",
        "scenario=poc",
        "policy=[mpdm,rbts]",
        "seeds=[0,1]",
        "lower_bound=true",
        "progress=false",
        f"output={out}",
    )
    assert result.code == 0, result.err
    data = _strict_json(out)
    assert len(data["lower_bound"]) == 2
    assert data["lower_bound_time_s"] >= 0
    assert len(data["policies"]["mpdm"]["gap_pct"]) == 2
    assert re.search(r"^lower bound: \d+\.\d s$", result.out, re.M)
    assert "gap to bound" in result.out
    assert "| lower bound |" in result.out


def test_lower_bound_skipped_in_paper_mode(tmp_path: Path, cli) -> None:
    out = tmp_path / "r.json"
    result = cli(
        "eval",
        "scenario=two_task",
        "policy=[mpdm]",
        "seeds=[0]",
        "lower_bound=true",
        "progress=false",
        f"output={out}",
    )
    assert result.code == 0, result.err
    data = _strict_json(out)
    assert (data["lower_bound"], data["lower_bound_time_s"]) == (None, None)
    assert "lower bound: skipped (drain mode only)" in result.out


def _cli(args: list[str], cwd: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [str(RTAW_EVAL), *args], cwd=cwd, capture_output=True, text=True, timeout=300
    )


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["sim.num_robots=0"], "sim.num_robots must be >= 1"),
        (["sim.queue_len=0"], "sim.queue_len must be >= 1"),
        (["layout.path=missing.map"], "layout file not found"),
        (["policy=[nope]"], "unknown policy 'nope'; available: "),
        (["tasks=file"], "tasks.path"),
        (["tasks=file", "tasks.path=missing.csv"], "task file not found"),
        (["navigator=sipp", "sim.noise_var=0.25"], "set sim.noise_mean=0 sim.noise_var=0"),
        (["navigator=cbs", "navigator.max_nodes=0"], "navigator.max_nodes must be a positive"),
        (["navigator=sipp", "+navigator.window=5"], "unknown config key 'navigator.window'"),
        (["compare_to=nope"], "compare_to=nope is not an evaluated policy"),
    ],
)
def test_cli_errors_are_one_line(args: list[str], message: str, cli) -> None:
    """Bad input: exit status 2, one clear line, no traceback."""
    result = cli("eval", *args, "progress=false")
    assert result.code == 2
    assert message in result.err
    assert len(result.err.strip().splitlines()) == 1
    assert "Traceback" not in result.err + result.out


def test_cli_unknown_group_option_lists_available(tmp_path: Path) -> None:
    """An unknown navigator: one line listing the available options (console script)."""
    proc = _cli(["navigator=dijkstra"], tmp_path)
    assert proc.returncode == 2
    assert proc.stderr.strip() == (
        "error: Could not find 'navigator/dijkstra'; available: astar, cbs, direct, pibt, sipp"
    )


def test_cli_multirun_writes_one_result_per_job(tmp_path: Path) -> None:
    """--multirun sweeps run out of the box, one results.json per job."""
    proc = _cli(
        ["--multirun", "scenario=poc", "policy=[mpdm]", "seeds=[0]", "navigator=direct,astar"],
        tmp_path,
    )
    assert proc.returncode == 0, proc.stderr
    results = sorted(tmp_path.glob("multirun/**/results.json"))
    assert len(results) == 2
    ttds = {json.loads(p.read_text())["config"]["navigator"]["name"]: p for p in results}
    assert set(ttds) == {"direct", "astar"}


@pytest.mark.parametrize(
    ("group", "option"), [(g, o) for g in ("model", "algo") for o in group_options(g)]
)
def test_every_training_option_composes(group: str, option: str) -> None:
    """Each model/algo option composes into the rtaw-train config and builds networks."""
    from rtaw_marl.models.checkpoint import build_networks

    cfg = compose(config_name="train", overrides=[f"{group}={option}"])
    actor, _ = build_networks(typed(cfg).model)
    assert sum(p.numel() for p in actor.parameters()) > 0
    assert cfg.algo.frames_per_batch % cfg.algo.minibatch_size == 0
    assert 0 < cfg.algo.policy_coeff <= 1


@pytest.mark.parametrize("launcher", ["basic", "joblib", "submitit_slurm"])
def test_table1_experiment_composes_with_every_launcher(launcher: str) -> None:
    """experiment=table1 sweeps rows x robot counts; local and SLURM launchers compose."""
    cfg = compose(
        config_name="eval",
        overrides=["experiment=table1", "row=D", f"hydra/launcher={launcher}"],
        return_hydra_config=True,
    )
    rows = "direct,A,B,C,D,E,direct_m100,A_m100,B_m100,C_m100,D_m100,E_m100"
    assert cfg.hydra.sweeper.params == {"row": rows}
    assert rows.split(",") == list(ROWS)  # experiment/table1.yaml sweeps every registered row
    assert (cfg.layout.preset, cfg.navigator.name) == ("D", "astar")
    assert list(cfg.pretrained) == ["D_astar_m10_long_plus", "D_astar_m10_long"]
    assert cfg.sim.episode_mode == "paper"
    assert list(cfg.policy) == ["mpdm", "rbts", "lookahead", "hungarian", "hindsight", "pretrained"]
    assert list(cfg.seeds) == list(range(20))


RULES = "policy=[mpdm,rbts,lookahead,hungarian,hindsight]"


@pytest.mark.parametrize(
    "overrides",
    [
        ["scenario=poc"],
        ["scenario=two_task", "sim.num_tasks=40"],
        ["scenario=two_task", "sim.num_tasks=40", "sim.episode_mode=drain"],
        *(
            [f"layout={layout}", "tasks=random", "sim.num_tasks=12"]
            for layout in ("open", "shelves", "warehouse", "A", "B", "C", "D", "E")
        ),
        *(
            [
                f"navigator={nav}",
                "layout=A",
                "tasks=random",
                "sim.num_robots=4",
                "sim.num_tasks=12",
            ]
            for nav in ("direct", "sipp", "cbs")
        ),
    ],
    ids=lambda o: " ".join(o),
)
def test_every_rule_runs_everywhere(overrides: list[str], cli, tmp_path: Path) -> None:
    """The rules and the hindsight reference run on every scenario, layout and navigator."""
    out = tmp_path / "r.json"
    result = cli("eval", RULES, *overrides, "seeds=[0,1]", "progress=false", f"output={out}")
    assert result.code == 0, result.err
    data = json.loads(out.read_text())
    assert set(data["policies"]) == {"mpdm", "rbts", "lookahead", "hungarian", "hindsight"}
    assert "hindsight (reference: knows the future)" in result.out


def test_the_old_name_of_pretrained_still_works_with_one_warning(tmp_path: Path, cli) -> None:
    """policy=rtaw (the package's and the paper network's name too) is policy=pretrained."""
    out = {name: tmp_path / f"{name}.json" for name in ("rtaw", "pretrained")}
    for name, path in out.items():
        result = cli(
            "eval", "scenario=poc", f"policy=[mpdm,{name}]", "pretrained=shelves_astar_m10_plus",
            "seeds=[0]", "progress=false", f"output={path}",
        )  # fmt: skip
        assert result.code == 0, result.err
        warned = "warning: policy=rtaw is deprecated, use policy=pretrained" in result.err
        assert warned == (name == "rtaw")
    old, new = (json.loads(p.read_text())["policies"] for p in out.values())
    assert old.keys() == new.keys()
    assert [v["ttd"] for v in old.values()] == [v["ttd"] for v in new.values()]


def test_a_large_seed_range_is_never_parsed_expanded(
    cli, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """``seeds='${range:0,100000}'`` reaches the first episode with every seed, and no
    override is parsed in its expanded form (parsing a list is quadratic in its length:
    10k seeds took 12.6 s to the first episode, 100k minutes)."""
    import rtaw_marl.cli.eval as eval_cli

    texts: list[str] = []
    parse = OverridesParser.parse_overrides

    def recording(self: OverridesParser, overrides: list[str]) -> object:
        texts.extend(overrides)
        return parse(self, overrides)

    seen: list[int] = []

    def first_episode(sim: object, policies: object, seeds: list[int], **kwargs: object) -> None:
        seen.append(len(seeds))
        raise KeyboardInterrupt

    monkeypatch.setattr(OverridesParser, "parse_overrides", recording)
    monkeypatch.setattr(eval_cli, "evaluate", first_episode)
    seeds = "seeds=${range:0,100000}"
    args = ["scenario=poc", "policy=mpdm", "progress=false", seeds, f"output={tmp_path / 'r.json'}"]
    result = cli("eval", *args)
    assert (result.code, seen) == (130, [100_000])
    # Everything parsed is an override as typed (Hydra's own parse), never the expansion.
    assert seeds in texts
    assert set(texts) <= {*args, "hydra.mode=RUN"}


@pytest.mark.parametrize(
    "setting",
    [
        ["scenario=poc"],  # 2 robots, a queue of 2, 10x10
        ["row=C", "sim.num_robots=37", "sim.queue_len=7", "sim.num_tasks=40"],
        ["scenario=open300_direct_m1000_random", "sim.num_tasks=60"],
    ],
)
def test_the_generalist_is_selected_by_name_on_any_scenario(
    cli, tmp_path: Path, setting: list[str]
) -> None:
    out = tmp_path / "results.json"
    result = cli(
        "eval", *setting, "policy=[mpdm,pretrained]", "pretrained=generalist_plus",
        "seeds=[0,1]", "progress=false", f"output={out}",
    )  # fmt: skip
    assert result.code == 0, result.err
    policies = json.loads(out.read_text())["policies"]
    assert set(policies) == {"mpdm", "generalist_plus"}
    assert all(ttd > 0 for ttd in policies["generalist_plus"]["ttd"])


def test_candidates_restrict_learned_policies_under_their_own_label(tmp_path: Path, cli) -> None:
    """``candidates=K`` evaluates the learned policy on the K nearest tasks, labelled
    ``NAME@kK`` (its own journal entries); it is one clear error when not >= 1."""
    out = tmp_path / "k.json"
    result = cli(
        "eval", "scenario=poc", "sim.queue_len=12", "policy=pretrained",
        "pretrained=shelves_astar_m10_plus", "candidates=4", "seeds=[0,1]", "progress=false",
        f"output={out}",
    )  # fmt: skip
    assert result.code == 0, result.err
    assert list(json.loads(out.read_text())["policies"]) == ["shelves_astar_m10_plus@k4"]
    bad = cli("eval", "scenario=poc", "candidates=0", "progress=false")
    assert bad.code == 2
    assert "candidates must be >= 1" in bad.err
    assert "Traceback" not in bad.err


def test_search_over_a_learned_policy_runs_under_its_own_label(tmp_path: Path, cli) -> None:
    """``policy=search search.policy=NAME`` evaluates NAME searched at decision time,
    labelled ``NAME+search`` beside the plain network, with its options recorded."""
    out = tmp_path / "s.json"
    result = cli(
        "eval", "scenario=poc", "policy=[pretrained,search]", "pretrained=shelves_astar_m10_plus",
        "search.policy=shelves_astar_m10_plus", "search.width=3", "search.horizon=2",
        "seeds=[0,1]", "progress=false", f"output={out}",
    )  # fmt: skip
    assert result.code == 0, result.err
    data = json.loads(out.read_text())
    assert list(data["policies"]) == ["shelves_astar_m10_plus", "shelves_astar_m10_plus+search"]
    assert data["config"]["search"] == {
        "policy": "shelves_astar_m10_plus", "width": 3, "horizon": 2, "leaf": 0.0,
        "propose": None,
    }  # fmt: skip


def test_matched_decisions_run_under_their_own_label(tmp_path: Path, cli) -> None:
    """``policy=matched matched=NAME candidates=K``: NAME deciding each timestep's free
    robots together, labelled ``NAME@kK+matched``; without ``candidates`` one line."""
    out = tmp_path / "m.json"
    result = cli(
        "eval", "scenario=poc", "sim.queue_len=12", "policy=[pretrained,matched]",
        "pretrained=shelves_astar_m10_plus", "matched=shelves_astar_m10_plus", "candidates=4",
        "seeds=[0,1]", "progress=false", f"output={out}",
    )  # fmt: skip
    assert result.code == 0, result.err
    data = json.loads(out.read_text())
    assert list(data["policies"]) == [
        "shelves_astar_m10_plus@k4", "shelves_astar_m10_plus@k4+matched"
    ]  # fmt: skip
    assert all(v > 0 for v in data["policies"]["shelves_astar_m10_plus@k4+matched"]["ttd"])
    for args, message in [
        (["policy=matched", "matched=shelves_astar_m10_plus"], "needs candidates=K"),
        (["policy=matched", "candidates=4"], "policy=matched needs matched=..."),
        (["matched=shelves_astar_m10_plus"], "matched=... given but policy does not include"),
    ]:
        bad = cli("eval", "scenario=poc", "progress=false", *args)
        assert bad.code == 2, args
        assert message in bad.err
        assert "Traceback" not in bad.err


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["policy=search"], "policy=search needs search.policy=... (one value or a list)"),
        (["search.policy=generalist_plus"], "search.policy=... given but policy does not include"),
        (["policy=search", "search.policy=nope"], "'nope' is neither a checkpoint file nor"),
        (["policy=search", "search.policy=[A_astar_m10,A_astar_m10]"], "names 'A_astar_m10' twice"),
        (["policy=search", "search.policy=A_astar_m10", "search.width=0"], "search.width must be"),
        (["policy=search", "search.policy=A_astar_m10", "search.leaf=-1"], "search.leaf must be"),
        (["policy=search", "search.policy=A_astar_m10", "search.depth=3"], "search.depth"),
    ],
)
def test_bad_search_is_one_line(cli, args: list[str], message: str) -> None:
    result = cli("eval", "scenario=poc", "progress=false", *args)
    assert result.code == 2
    assert message in result.err
    assert "Traceback" not in result.err
    assert len(result.err.strip().splitlines()) <= 2  # the layout line, then the error


# --------------------------------------------------------------------------- your policy
USER_MODULE = """
import numpy as np


def first_queued(sim):
    return int(np.flatnonzero(sim.queue_mask)[0])


class Nearest:
    name = "Nearest"

    def reset(self, seed=None):
        pass

    def act_sim(self, sim):
        return int(np.where(sim.queue_mask, sim.robot_distances(), np.inf).argmin())
"""


def test_a_user_policy_by_module_and_name(cli, tmp_path: Path) -> None:
    """``policy=[mpdm,my_rules:first_queued,my_rules:Nearest]`` imports the user's module
    from the working directory; labels are the attribute names; the per-episode CSV sits
    beside results.json, and no lock file is left."""
    (tmp_path / "my_rules.py").write_text(USER_MODULE)
    out = tmp_path / "r.json"
    result = cli(
        "eval", "scenario=poc", "policy=[mpdm,my_rules:first_queued,my_rules:Nearest]",
        "seeds=[0,1]", f"output={out}", "progress=false",
    )  # fmt: skip
    assert result.code == 0, result.err
    policies = json.loads(out.read_text())["policies"]
    assert list(policies) == ["mpdm", "first_queued", "Nearest"]
    assert "| first_queued |" in result.out
    rows = (tmp_path / "r.csv").read_text().splitlines()
    assert rows[0].startswith("policy,seed,ttd,")
    assert [r.split(",")[:2] for r in rows[1:]] == [
        [p, s] for p in ("mpdm", "first_queued", "Nearest") for s in ("0", "1")
    ]
    assert not list(tmp_path.glob(".*.lock"))


@pytest.mark.parametrize(
    ("policy", "message"),
    [
        ("no_such_module:Rule", "no module named 'no_such_module'"),
        ("my_rules:Nearst", "my_rules has no 'Nearst'; its callables: Nearest, first_queued"),
        ("my_rules:", "a user policy is named module:Name"),
    ],
)
def test_a_bad_user_policy_is_one_line(cli, tmp_path: Path, policy: str, message: str) -> None:
    (tmp_path / "my_rules.py").write_text(USER_MODULE)
    result = cli("eval", "scenario=poc", f"policy=[mpdm,'{policy}']", "seeds=[0]")
    assert result.code == 2
    assert message in result.err
    assert "Traceback" not in result.err


def test_checkpoint_labels_are_short_and_distinct() -> None:
    from rtaw_marl.policies.labels import checkpoint_labels

    assert checkpoint_labels(["runs/demo/checkpoints/best.pt"]) == ["demo/best"]
    assert checkpoint_labels(["generalist_plus"]) == ["generalist_plus"]
    assert checkpoint_labels(["a/x/checkpoints/best.pt", "b/x/checkpoints/best.pt"]) == [
        "a/x/best",
        "b/x/best",
    ]


def test_an_output_named_like_its_table_is_refused(cli, tmp_path: Path) -> None:
    result = cli("eval", "scenario=poc", "seeds=[0]", f"output={tmp_path / 'r.csv'}")
    assert result.code == 2
    assert "name a .json file" in result.err
