"""``recipe=new_map`` measured on three maps the project never trained on.

Usage::

    python -m benchmarks.scripts.new_map_recipe                  # train and evaluate what is missing
    python -m benchmarks.scripts.new_map_recipe --render         # the table from the stored runs
    python -m benchmarks.scripts.new_map_recipe --render --write docs/training.md

For each map: ``rtaw-train recipe=new_map layout=file layout.path=MAP sim.num_robots=M``
(timed as a user runs it, its verdict included), then ``rtaw-eval`` of the five rules,
the shipped generalist and the run's ``best.pt`` on the evaluation seeds 0-19 with
``compare_to=best`` (the best rule chosen on seeds 1000-1019), and of ``best.pt``
searched at decision time (``policy=search search.policy=best.pt``). Runs go to
``runs/new_map/<name>``; ``--render`` stores each map's figures in
``benchmarks/data/new_map_recipe.json`` and prints (or ``--write``\\ s, between the
``new_map`` markers) the table.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from pathlib import Path

from benchmarks.study import replace_section
from rtaw_marl.evaluation.report import diff_cell, markdown_table
from rtaw_marl.evaluation.stats import paired_difference
from rtaw_marl.utils.atomic import atomic_write

ROOT = Path(__file__).resolve().parents[2]
SHARED = ROOT.parent / "shared" / "maps"
RUNS = ROOT / "runs" / "new_map"
DATA = ROOT / "benchmarks" / "data" / "new_map_recipe.json"

#: name -> (map file under ../shared/maps, robots): none of them in any training mix.
MAPS: dict[str, tuple[str, int]] = {
    "movingai_10_20_10_2_2_m20": ("movingai/warehouse-10-20-10-2-2.map", 20),
    "mapd_warehouse_m20": ("mapd/warehouse.map", 20),
    "movingai_20_40_10_2_1_m50": ("movingai/warehouse-20-40-10-2-1.map", 50),
}
POLICIES = "policy=[mpdm,rbts,lookahead,hungarian,batch,pretrained,checkpoint]"


def setting(name: str) -> list[str]:
    """The map's keys, as a user types them."""
    path, robots = MAPS[name]
    return ["layout=file", f"layout.path={SHARED / path}", f"sim.num_robots={robots}"]


def train_command(name: str) -> list[str]:
    """The recipe's command for one map."""
    out = RUNS / name
    return ["rtaw-train", "recipe=new_map", *setting(name), f"output_dir={out}", "progress=false"]


def eval_command(name: str) -> list[str]:
    """The held-out evaluation of the run's ``best.pt`` beside the rules and the generalist."""
    best = RUNS / name / "checkpoints" / "best.pt"
    return [
        "rtaw-eval", *setting(name), POLICIES, "pretrained=generalist_plus", f"checkpoint={best}",
        "seeds=${range:0,20}", "compare_to=best", f"output={RUNS / name}.eval.json",
        "progress=false",
    ]  # fmt: skip


def search_command(name: str) -> list[str]:
    """The run's ``best.pt`` searched at decision time (``policy=search``) beside the rules."""
    best = RUNS / name / "checkpoints" / "best.pt"
    return [
        "rtaw-eval", *setting(name), "policy=[mpdm,rbts,lookahead,hungarian,batch,search]",
        f"search.policy={best}", "seeds=${range:0,20}", "compare_to=best",
        f"output={RUNS / name}.search.json", "progress=false",
    ]  # fmt: skip


def run(name: str) -> None:
    """Train (timed) and evaluate one map, skipping what is done."""
    bin_dir = Path(sys.executable).parent
    out = RUNS / name
    if not (out / "train_seconds").exists():
        began = time.perf_counter()
        cmd = train_command(name)
        subprocess.run([str(bin_dir / cmd[0]), *cmd[1:]], check=True)
        (out / "train_seconds").write_text(f"{time.perf_counter() - began:.0f}\n")
    for suffix, command in ((".eval.json", eval_command), (".search.json", search_command)):
        if not Path(f"{out}{suffix}").exists():
            cmd = command(name)
            subprocess.run([str(bin_dir / cmd[0]), *cmd[1:]], check=True)


def figures(name: str) -> dict[str, object]:
    """One map's stored figures: the verdict, the held-out comparison, the time."""
    out = RUNS / name
    verdict = json.loads((out / "verdict.json").read_text())
    results = json.loads(Path(f"{out}.eval.json").read_text())
    ttd = {p: v["ttd"] for p, v in results["policies"].items()}
    rule = results["best_rule"]["name"]
    label = next(p for p in ttd if p.endswith("/best"))
    searched = json.loads(Path(f"{out}.search.json").read_text())["policies"]
    ttd["searched"] = next(v["ttd"] for p, v in searched.items() if p.endswith("+search"))
    if searched[rule]["ttd"] != ttd[rule]:  # the same episodes, so the pairing holds
        raise SystemExit(f"{name}: the two evaluations' {rule} episodes differ")
    seconds = int((out / "train_seconds").read_text())
    return {
        "map": MAPS[name][0], "robots": MAPS[name][1], "seconds": seconds,
        "verdict": verdict, "best_rule": rule, "recipe": label,
        "ttd": {p: ttd[p] for p in (rule, "generalist_plus", label, "searched")},
        "command": " ".join(train_command(name)),
    }  # fmt: skip


def render(stored: dict[str, dict]) -> str:
    """The markdown table of the stored figures."""
    rows = []
    for f in stored.values():
        ttd, rule = f["ttd"], f["best_rule"]
        mean = sum(ttd[f["recipe"]]) / len(ttd[f["recipe"]])
        rows.append([
            f"`{Path(f['map']).stem}`, M={f['robots']}", rule,
            f"{mean:,.0f}",
            diff_cell(paired_difference(ttd[rule], ttd["generalist_plus"])),
            diff_cell(paired_difference(ttd[rule], ttd[f["recipe"]])),
            f["verdict"]["outcome"],
            diff_cell(paired_difference(ttd[rule], ttd["searched"])),
            f"{f['seconds'] / 60:.1f} min",
        ])  # fmt: skip
    head = ["map, robots", "best rule (seeds 1000-1019)", "recipe's TTD",
            "generalist vs the best rule", "recipe vs the best rule", "verdict (its own run)",
            "recipe searched vs the best rule", "rtaw-train, verdict included"]  # fmt: skip
    return markdown_table(head, rows)


def main(argv: list[str] | None = None) -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--render", action="store_true", help="the table from the stored runs")
    p.add_argument("--write", type=Path, help="replace the page's new_map section")
    args = p.parse_args(argv)
    if not args.render:
        for name in MAPS:
            run(name)
    stored = {name: figures(name) for name in MAPS if (RUNS / name / "verdict.json").exists()}
    if stored:
        text = json.dumps(stored, indent=1) + "\n"
        atomic_write(DATA, lambda fh: fh.write(text.encode()))
    elif DATA.exists():
        stored = json.loads(DATA.read_text())
    table = render(stored)
    print(table)
    if args.write:
        replace_section(args.write, "new_map", table)


if __name__ == "__main__":
    main()
