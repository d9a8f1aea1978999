"""What a learned policy does differently from MPDM and ``lookahead``: docs/analysis.md.

Usage::

    python experiments/analysis.py                     # RTAW+ and RTAW, rows C and Direct
    python experiments/analysis.py --seeds 5 --rows C  # quicker
    python experiments/analysis.py --checkpoint runs/x/checkpoints/best.pt --out /tmp/a.md

Each learned policy plays its own greedy episodes on the evaluation seeds 0..N-1 of each
row (Table I: 10 robots, 500 designated tasks, a queue of 10, ``drain`` mode). At every
decision along its trajectory the script also asks MPDM (nearest task) and ``lookahead``
(H = 3) what they would choose in the same state, and records:

* whether the policy picks a *nearest* task (smallest distance ``k``, within MPDM's tie
  tolerance: MPDM breaks such ties at random, so this is agreement with MPDM up to its
  tie-breaking) and whether it picks one of lookahead's choices (lowest lookahead cost,
  same tolerance);
* when it deviates from the nearest task: the extra distance accepted
  (``k_chosen - k_nearest``, cells); whether the nearest task is *contested* (every
  nearest task has a rival, another robot, arriving before the acting robot:
  ``rival_1 < 0`` in :data:`rtaw_marl.envs.features.RELATION_FEATURES`); whether the
  chosen task is uncontested; whether its ``chain`` (distance from its destination to
  the nearest other queued origin) is shorter than the nearest task's.

``lookahead``'s own trajectory gets the same statistics, for reference, and MPDM's own
episodes give the TTD baseline. ``--policies`` takes registry entries
(``C_astar_m10_plus``), used as is on every row, or the labels ``RTAW`` / ``RTAW+``,
which mean each row's own pretrained entry (as in Table I: ``C_astar_m10_long`` and
``C_astar_m10_long_plus`` on layout C, ``open60_direct_m10_long[_plus]`` on Direct).
``--checkpoint`` adds checkpoint files; given alone, it replaces the default policies.
A policy that does not load is skipped with a warning. The page is written atomically.
"""

from __future__ import annotations

import argparse
import shlex
import sys
import time
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from rtaw_marl.envs.features import RELATION_FEATURES, sim_relations
from rtaw_marl.errors import ConfigError
from rtaw_marl.evaluation.evaluate import SimPolicy, run_episode
from rtaw_marl.policies import make_baseline
from rtaw_marl.policies.lookahead import lookahead_costs
from rtaw_marl.policies.pretrained.registry import pretrained_path
from rtaw_marl.sim.builder import SimSpec
from rtaw_marl.sim.core import WarehouseSim
from rtaw_marl.utils.atomic import atomic_write

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_OUT = ROOT / "docs" / "analysis.md"
#: Table I's simulator settings (drain mode).
ENV = {"num_robots": 10, "num_tasks": 500, "queue_len": 10, "episode_mode": "drain"}
#: Learned label -> suffix of the row's pretrained registry entry.
LEARNED = {"RTAW": "_long", "RTAW+": "_long_plus"}
DEFAULT_POLICIES = "RTAW+,RTAW"
LOOKAHEAD = "lookahead"
#: Relative tolerance of a tie, as the rules use it (``baselines._TIE_RTOL``).
TIE_RTOL = 1e-6
#: A rival "arrives first" when its arrival minus ``k`` is below this (units of ``L``).
RIVAL_EPS = 1e-6
RIVAL_1 = RELATION_FEATURES.index("rival_1")
CHAIN = RELATION_FEATURES.index("chain")
#: Fewer deviations than this: a finding about them says the sample is small.
MIN_SAMPLE = 30


@dataclass(frozen=True)
class Row:
    """One Table I setting: label, layout, navigator and its pretrained scenario."""

    label: str
    short: str
    layout: dict[str, object]
    navigator: str
    scenario: str


ROWS: dict[str, Row] = {
    "direct": Row("Direct (open 60x60)", "Direct",
                  {"name": "open", "width": 60, "height": 60}, "direct", "open60_direct_m10"),
    **{p: Row(f"A* layout {p}", p, {"name": "preset", "preset": p, "width": 60, "height": 60},
              "astar", f"{p}_astar_m10") for p in "ABCDE"},
}  # fmt: skip


@dataclass(frozen=True)
class Decision:
    """How one choice relates to MPDM's and lookahead's in the same state.

    Attributes:
        nearest: The chosen task is a nearest one (MPDM's choice, up to ties).
        lookahead: The chosen task is one of lookahead's choices.
        lookahead_nearest: Lookahead would pick a nearest task.
        extra: ``k_chosen - k_nearest`` in cells (0 when ``nearest``).
        contested: Every nearest task has a rival arriving before the acting robot.
        chosen_free: No rival arrives at the chosen task before the acting robot.
        shorter_chain: The chosen task's chain is shorter than every nearest task's.
    """

    nearest: bool
    lookahead: bool
    lookahead_nearest: bool
    extra: float
    contested: bool
    chosen_free: bool
    shorter_chain: bool


@dataclass(frozen=True)
class Summary:
    """Statistics of one trajectory set (one policy on one row, all seeds pooled).

    Shares are fractions in ``[0, 1]``; ``None`` where their denominator is empty.
    ``name`` is the policy as asked for (``RTAW+``, an entry, a path, ``lookahead``),
    ``policy`` its label on this row; ``short`` is the row's short name.
    """

    row: str
    short: str
    name: str
    policy: str
    seeds: int
    decisions: int
    ttd: float
    mpdm_ttd: float
    nearest: float
    lookahead: float
    deviations: int
    extra_mean: float | None
    extra_median: float | None
    contested_in_deviations: float | None
    contested_overall: float | None
    deviate_if_contested: float | None
    deviate_if_uncontested: float | None
    chosen_free: float | None
    shorter_chain: float | None
    lookahead_deviations: int
    agree_if_lookahead_deviates: float | None
    nearest_if_lookahead_deviates: float | None


# --------------------------------------------------------------------------- decisions
class Probe:
    """MPDM and lookahead asked about the current state; their own tie-breaking
    generators are separate from any policy driving the simulator.

    Args:
        sim: The simulator (for its navigator and layout scale).
    """

    def __init__(self, sim: WarehouseSim) -> None:
        self.mpdm = make_baseline("mpdm", sim.navigator, sim.layout.scale)
        self.lookahead = make_baseline(LOOKAHEAD, sim.navigator, sim.layout.scale)
        self.horizon: int = self.lookahead.horizon

    def classify(self, sim: WarehouseSim, slot: int) -> Decision:
        """Relate ``slot``, about to be given to the selected robot, to the rules' choices.

        Raises:
            RuntimeError: A rule's own choice lies outside the tie set computed here.
        """
        mask = sim.queue_mask
        k = sim.robot_distances()
        nearest = ties(k, mask)
        ahead = lookahead_set(sim, self.horizon)
        for rule, allowed in ((self.mpdm, nearest), (self.lookahead, ahead)):
            if not allowed[rule.act_sim(sim)]:  # act_sim only reads the simulator
                raise RuntimeError(f"{rule.name} chose outside its tie set at t={sim.time}")
        relations, _ = sim_relations(sim)
        first = mask & (relations[:, RIVAL_1] < -RIVAL_EPS)
        chain = relations[:, CHAIN]
        return Decision(
            nearest=bool(nearest[slot]),
            lookahead=bool(ahead[slot]),
            lookahead_nearest=bool((ahead & nearest).any()),
            extra=float(k[slot] - k[mask].min()),
            contested=bool(first[nearest].all()),
            chosen_free=not bool(first[slot]),
            shorter_chain=bool(chain[slot] < chain[nearest].min()),
        )


def ties(values: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """``bool [N]``: the masked slots whose value is the smallest, within :data:`TIE_RTOL`."""
    best = float(values[mask].min())
    return mask & (values <= best + TIE_RTOL * max(1.0, best))


def end_distances(sim: WarehouseSim) -> np.ndarray:
    """``float64 [M + N, N]``: distances from each robot's cell (rows ``0..M-1``), then
    from each queued destination, to each queued origin; ``inf`` in empty slots' columns
    (rows of empty slots hold meaningless values that the rollout never reads)."""
    ends = np.vstack([sim.distance_matrix(), sim.chain_distances()])
    ends[:, ~sim.queue_mask] = np.inf
    return ends


def lookahead_set(sim: WarehouseSim, horizon: int) -> np.ndarray:
    """``bool [N]``: the slots of least lookahead cost (``Lookahead.act_sim`` picks one)."""
    mask = sim.queue_mask
    costs = lookahead_costs(
        sim.robot_distances(), end_distances(sim), sim.robot, sim.robot_free_at, sim.time,
        sim.queue_length, mask, horizon, sim.config.noise_mean,
    )  # fmt: skip
    return ties(costs, mask)


def play(
    sim: WarehouseSim, policy: SimPolicy, seeds: Sequence[int]
) -> tuple[list[Decision], list[float]]:
    """Run ``policy``'s own episodes and classify each of its decisions.

    Returns:
        Every decision over all seeds, and the TTD of each episode.
    """
    probe = Probe(sim)
    decisions, ttds = [], []
    for seed in seeds:
        sim.reset(seed)
        policy.reset(seed)
        probe.mpdm.reset(seed)
        probe.lookahead.reset(seed)
        while not sim.done:
            slot = policy.act_sim(sim)
            decisions.append(probe.classify(sim, slot))
            sim.step(slot)
        ttds.append(sim.metrics().ttd)
    return decisions, ttds


# --------------------------------------------------------------------------- statistics
_FIELDS = tuple(Decision.__dataclass_fields__)


def share(flags: np.ndarray, where: np.ndarray | None = None) -> float | None:
    """Fraction of ``flags`` that hold (among ``where``); ``None`` when empty."""
    picked = flags if where is None else flags[where]
    return float(picked.mean()) if picked.size else None


def summarise(
    row: Row, name: str, label: str, decisions: list[Decision], ttds: list[float], mpdm_ttd: float
) -> Summary:
    """Pool one policy's decisions on one row into a :class:`Summary` (``name``: the
    policy as asked for, ``label``: its label on this row)."""
    field = {f: np.array([getattr(d, f) for d in decisions]) for f in _FIELDS}
    dev = ~field["nearest"]
    contested = field["contested"]
    la_dev = ~field["lookahead_nearest"]
    extra = field["extra"][dev]
    return Summary(
        row=row.label, short=row.short, name=name, policy=label,
        seeds=len(ttds), decisions=len(decisions),
        ttd=float(np.mean(ttds)), mpdm_ttd=mpdm_ttd,
        nearest=float(field["nearest"].mean()), lookahead=float(field["lookahead"].mean()),
        deviations=int(dev.sum()),
        extra_mean=float(extra.mean()) if extra.size else None,
        extra_median=float(np.median(extra)) if extra.size else None,
        contested_in_deviations=share(contested, dev), contested_overall=share(contested),
        deviate_if_contested=share(dev, contested), deviate_if_uncontested=share(dev, ~contested),
        chosen_free=share(field["chosen_free"], dev),
        shorter_chain=share(field["shorter_chain"], dev),
        lookahead_deviations=int(la_dev.sum()),
        agree_if_lookahead_deviates=share(field["lookahead"], la_dev),
        nearest_if_lookahead_deviates=share(field["nearest"], la_dev),
    )  # fmt: skip


# --------------------------------------------------------------------------- runs
@dataclass(frozen=True)
class Learned:
    """A learned policy to analyse on one row.

    Attributes:
        name: As asked for: ``RTAW+``, a registry entry or a checkpoint path.
        label: Its label on the row (``RTAW+ (C_astar_m10_long_plus)``).
        path: The checkpoint file.
    """

    name: str
    label: str
    path: Path


def resolve(
    names: Iterable[str], checkpoints: Iterable[str], row: Row
) -> tuple[list[Learned], list[str]]:
    """The learned policies of ``row``, and the labels of registry entries that are
    missing (warned about and left out)."""
    out, missing = [], []
    for name in names:
        entry = row.scenario + LEARNED[name] if name in LEARNED else name
        label = f"{name} ({entry})" if name in LEARNED else name
        try:
            out.append(Learned(name, label, pretrained_path(entry)))
        except ConfigError as err:
            print(f"warning: {row.label}: {label} skipped: {err}", file=sys.stderr, flush=True)
            missing.append(label)
    out += [Learned(path, path, Path(path)) for path in checkpoints]
    return out, missing


def analyse_row(
    row: Row, policies: list[Learned], seeds: Sequence[int]
) -> tuple[list[Summary], list[str]]:
    """Summaries of each learned policy, then of lookahead, on ``row``; and the labels of
    the policies that did not load."""
    from rtaw_marl.policies.network import load_policy  # torch: only when running

    sim = SimSpec.of(ENV, row.layout, row.navigator, "designated").build()
    mpdm = make_baseline("mpdm", sim.navigator, sim.layout.scale)
    mpdm_ttd = float(np.mean([run_episode(sim, mpdm, s).ttd for s in seeds]))
    players: list[tuple[str, str, SimPolicy]] = []
    skipped = []
    for p in policies:
        try:
            players.append((p.name, p.label, load_policy(p.path, name=p.label)))
        except ConfigError as err:
            print(f"warning: {row.label}: {p.label} skipped: {err}", file=sys.stderr, flush=True)
            skipped.append(p.label)
    rule = make_baseline(LOOKAHEAD, sim.navigator, sim.layout.scale)
    players.append((LOOKAHEAD, LOOKAHEAD, rule))
    out = []
    for name, label, policy in players:
        start = time.perf_counter()
        decisions, ttds = play(sim, policy, seeds)
        out.append(summarise(row, name, label, decisions, ttds, mpdm_ttd))
        took = time.perf_counter() - start
        print(f"done {row.label}: {label} ({took:.0f} s)", file=sys.stderr, flush=True)
    return out, skipped


# --------------------------------------------------------------------------- page
def pct(value: float | None) -> str:
    """``42%`` (``-`` for None)."""
    return "-" if value is None else f"{100 * value:.0f}%"


def cells(value: float | None) -> str:
    """``3.2`` (``-`` for None)."""
    return "-" if value is None else f"{value:.1f}"


def vs_mpdm(s: Summary) -> str:
    """Mean TTD and its change against MPDM's on the same seeds (negative: less TTD)."""
    return f"{s.ttd:.0f} ({100 * (s.ttd / s.mpdm_ttd - 1):+.1f}%)"


def markdown(head: list[str], rows: list[list[str]]) -> str:
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    return "\n".join([*lines, *("| " + " | ".join(r) + " |" for r in rows)])


def choices_table(summaries: list[Summary]) -> str:
    """Per policy and row: TTD, agreement with MPDM and lookahead, extra distance."""
    head = ["row", "policy", "decisions", "mean TTD (vs MPDM)", "picks nearest",
            "extra cells when not (mean / median)", "picks lookahead's",
            "when lookahead leaves nearest: same / nearest (n)"]  # fmt: skip
    rows = []
    for s in summaries:
        own = s.name == LOOKAHEAD
        la = "(itself)" if own else pct(s.lookahead)
        when = "(itself)" if own else (f"{pct(s.agree_if_lookahead_deviates)} / "
                                       f"{pct(s.nearest_if_lookahead_deviates)} "
                                       f"({s.lookahead_deviations})")  # fmt: skip
        rows.append([s.row, s.policy, str(s.decisions), vs_mpdm(s), pct(s.nearest),
                     f"{cells(s.extra_mean)} / {cells(s.extra_median)}", la, when])  # fmt: skip
    return markdown(head, rows)


def situations_table(summaries: list[Summary]) -> str:
    """Per policy and row: in which situations it leaves the nearest task."""
    head = ["row", "policy", "deviations", "nearest contested: in deviations / in all",
            "deviation rate: nearest contested / not", "chosen uncontested",
            "chosen has shorter chain"]  # fmt: skip
    rows = [[s.row, s.policy, str(s.deviations),
             f"{pct(s.contested_in_deviations)} / {pct(s.contested_overall)}",
             f"{pct(s.deviate_if_contested)} / {pct(s.deviate_if_uncontested)}",
             pct(s.chosen_free), pct(s.shorter_chain)] for s in summaries]  # fmt: skip
    return markdown(head, rows)


# --------------------------------------------------------------------------- findings
Pair = tuple[Summary, Summary]  # a learned policy's summary and lookahead's, same row


def by_policy(summaries: list[Summary]) -> dict[str, list[Pair]]:
    """Learned policy name -> (its summary, lookahead's) on each row it ran on."""
    reference = {s.row: s for s in summaries if s.name == LOOKAHEAD}
    out: dict[str, list[Pair]] = {}
    for s in summaries:
        if s.name != LOOKAHEAD:
            out.setdefault(s.name, []).append((s, reference[s.row]))
    return out


def verdict(pairs: Iterable[tuple[float | None, float | None]], more: str, less: str) -> str:
    """``more`` when the first value exceeds the second in every pair with both, ``less``
    when it is below in every one, else ``more`` qualified as holding on some rows only."""
    both = [(a, b) for a, b in pairs if a is not None and b is not None]
    if both and all(a > b for a, b in both):
        return more
    if both and all(a < b for a, b in both):
        return less
    return f"{more} on some rows only" if both else f"{more}: not measurable"


def _few(s: Summary) -> str:
    return f", only {s.deviations} deviations" if s.deviations < MIN_SAMPLE else ""


def nearest_clause(name: str, pairs: list[Pair]) -> str:
    lead = verdict(((s.nearest, la.nearest) for s, la in pairs),
                   "keeps the nearest task more often than lookahead",
                   "leaves the nearest task more often than lookahead")  # fmt: skip
    nums = "; ".join(f"{s.short}: {pct(s.nearest)} vs {pct(la.nearest)}" for s, la in pairs)
    return f"`{name}` {lead} ({nums})"


def extra_clause(name: str, pairs: list[Pair]) -> str:
    lead = verdict(((s.extra_mean, la.extra_mean) for s, la in pairs),
                   "accepts more extra distance than lookahead",
                   "accepts less extra distance than lookahead")  # fmt: skip
    nums = "; ".join(f"{s.short}: mean {cells(s.extra_mean)} vs {cells(la.extra_mean)}, "
                     f"median {cells(s.extra_median)} vs {cells(la.extra_median)}{_few(s)}"
                     for s, la in pairs)  # fmt: skip
    return f"`{name}` {lead} ({nums})"


def contested_clause(name: str, rows: list[Summary]) -> str:
    lead = verdict(((s.deviate_if_contested, s.deviate_if_uncontested) for s in rows),
                   "leaves the nearest task more often when a rival reaches it first",
                   "leaves the nearest task less often when a rival reaches it first")  # fmt: skip
    nums = "; ".join(f"{s.short}: {pct(s.deviate_if_contested)} vs "
                     f"{pct(s.deviate_if_uncontested)} otherwise" for s in rows)  # fmt: skip
    return f"`{name}` {lead} ({nums})"


def target_clause(name: str, pairs: list[Pair]) -> str:
    free = verdict(((s.chosen_free, la.chosen_free) for s, la in pairs),
                   "more often uncontested", "less often uncontested")  # fmt: skip
    chain = verdict(((s.shorter_chain, la.shorter_chain) for s, la in pairs),
                    "more often has a shorter chain", "less often has a shorter chain")  # fmt: skip
    nums = "; ".join(f"{s.short}: uncontested {pct(s.chosen_free)} vs {pct(la.chosen_free)}, "
                     f"shorter chain {pct(s.shorter_chain)} vs {pct(la.shorter_chain)}"
                     for s, la in pairs)  # fmt: skip
    return f"The task `{name}` takes instead, against lookahead's: {free}; {chain} ({nums})"


def agree_clause(name: str, pairs: list[Pair]) -> str:
    rows = [s for s, _ in pairs]
    lead = verdict(((s.agree_if_lookahead_deviates, 0.5) for s in rows),
                   "mostly makes the same choice", "mostly does not follow it")  # fmt: skip
    nums = "; ".join(f"{s.short}: of {s.lookahead_deviations} such decisions, same choice "
                     f"{pct(s.agree_if_lookahead_deviates)}, nearest task "
                     f"{pct(s.nearest_if_lookahead_deviates)}" for s in rows)  # fmt: skip
    return f"`{name}` {lead} ({nums})"


def ttd_clause(name: str, pairs: list[Pair]) -> str:
    return f"`{name}`: " + "; ".join(
        f"{s.short}: {100 * (s.ttd / s.mpdm_ttd - 1):+.1f}% vs MPDM, "
        f"{100 * (s.ttd / la.ttd - 1):+.1f}% vs lookahead"
        for s, la in pairs
    )


def findings(summaries: list[Summary]) -> list[str]:
    """Bullets templated from the measured numbers: one topic each, a clause per policy
    (lead words chosen by comparing the numbers, the numbers in brackets)."""
    learned = by_policy(summaries)
    reference = [s for s in summaries if s.name == LOOKAHEAD]
    rules = [contested_clause(LOOKAHEAD, reference)]
    lines = [
        ("Nearest task (share of decisions, policy vs lookahead)", nearest_clause),
        ("Extra distance when leaving it (cells, policy vs lookahead)", extra_clause),
        ("Where they leave it (deviation rate, nearest task contested vs not)", None),
        ("What they take instead (share of deviations, policy vs lookahead)", target_clause),
        ("When lookahead leaves the nearest task", agree_clause),
        ("Mean TTD on these seeds (means only; paired intervals in [results.md](results.md))",
         ttd_clause),
    ]  # fmt: skip
    out = []
    for title, clause in lines:
        if clause is None:
            parts = [contested_clause(n, [s for s, _ in p]) for n, p in learned.items()] + rules
        else:
            parts = [clause(n, p) for n, p in learned.items()]
        if parts:
            out.append(f"- **{title}**: " + " ".join(f"{c}." for c in parts))
    return out


# --------------------------------------------------------------------------- page
METHOD = """\
Each policy plays its own greedy episodes on the evaluation {seeds} (Table I
settings: 10 robots, 500 designated tasks, a queue of 10, `drain` mode). At every
decision along its trajectory, MPDM (nearest task) and `lookahead` (H = {horizon}) are
asked what they would choose in the same state; `lookahead`'s own trajectory is measured
the same way for reference, and MPDM's own episodes give the TTD baseline. Command:

```
{command}
```

- *picks nearest*: the chosen task has the smallest distance `k` (ties count: MPDM
  breaks them at random). A *deviation* is any other choice; its *extra cells* are
  `k_chosen - k_nearest`. *picks lookahead's*: the chosen task has the least lookahead
  cost (ties count).
- A task is *contested* when another robot arrives at its origin before the acting
  robot (`rival_1 < 0`: its time until free plus its distance); the *nearest task is
  contested* when every nearest task is. *Chain*: distance from the task's destination
  to the nearest other queued origin.
- All decisions of all seeds are pooled; shares of deviations are over the deviations.
"""


def page(summaries: list[Summary], seeds: int, command: str, skipped: list[str]) -> str:
    """The analysis page: method, the two tables, the findings."""
    stamp = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())
    span = "seed 0" if seeds == 1 else f"seeds 0-{seeds - 1}"
    horizon = make_baseline(LOOKAHEAD).horizon
    parts = [
        "# What the learned policies do differently",
        f"_Generated {stamp} by `experiments/analysis.py`._",
        "How often a learned policy leaves the nearest task (MPDM's choice), how much extra "
        "distance it then accepts, in which situations, and how that compares with "
        "`lookahead`, the strongest hand-written rule.",
        "## How it was measured",
        METHOD.format(seeds=span, horizon=horizon, command=command).rstrip(),
        "## Choices",
        choices_table(summaries),
        "## Situations of the deviations",
        situations_table(summaries),
        "## Findings",
        "\n".join(findings(summaries)),
    ]
    if skipped:
        parts.append("Not loaded (skipped): " + ", ".join(skipped) + ".")
    return "\n\n".join(parts) + "\n"


# --------------------------------------------------------------------------- main
def parse_args(argv: list[str] | None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--seeds", type=int, default=20, help="evaluation seeds 0..N-1")
    parser.add_argument(
        "--policies",
        default=None,
        help=f"comma-separated registry entries or RTAW/RTAW+ (default {DEFAULT_POLICIES}; "
        "none when only --checkpoint is given)",
    )
    parser.add_argument("--checkpoint", action="append", default=[], help="checkpoint file")
    parser.add_argument("--rows", default="C,direct", help=f"comma-separated: {', '.join(ROWS)}")
    parser.add_argument("--out", type=Path, default=DEFAULT_OUT, help="the page to write")
    args = parser.parse_args(argv)
    rows = [r if r == "direct" else r.upper() for r in args.rows.lower().split(",") if r]
    bad = [r for r in rows if r not in ROWS]
    if bad or not rows or args.seeds < 1:
        parser.error(f"--rows takes {', '.join(ROWS)} and --seeds >= 1 (got {args.rows!r})")
    args.rows = rows
    if args.policies is None:
        args.policies = "" if args.checkpoint else DEFAULT_POLICIES
    args.policies = [p for p in args.policies.split(",") if p]
    return args


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    given = sys.argv[1:] if argv is None else argv
    command = shlex.join(["python", "experiments/analysis.py", *given])
    import torch

    torch.set_num_threads(1)  # tiny networks: threads only contend with other jobs
    seeds = list(range(args.seeds))
    summaries: list[Summary] = []
    skipped: list[str] = []
    for key in args.rows:
        policies, missing = resolve(args.policies, args.checkpoint, ROWS[key])
        row_summaries, not_loaded = analyse_row(ROWS[key], policies, seeds)
        summaries += row_summaries
        skipped += [f"{s} on {ROWS[key].label}" for s in [*missing, *not_loaded]]
    text = page(summaries, args.seeds, command, skipped)
    atomic_write(args.out, lambda fh: fh.write(text.encode()))
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
