"""The registry of shipped pretrained RTAW policies.

Each entry is the exact ``rtaw-train`` overrides that produced ``<name>.pt`` in this
folder (``experiments/train_pretrained.py`` reruns them; every checkpoint also records
its command). Policies trained with 10 robots also run with 100 or 1000: the networks'
sizes do not depend on them.
"""

from __future__ import annotations

import sys
from pathlib import Path

from rtaw_marl.errors import ConfigError, unknown_name

__all__ = [
    "CONTINUED",
    "CURRICULUM",
    "CURRICULUM_FRAMES",
    "LONG_FRAMES",
    "PRETRAINED",
    "SCENARIOS",
    "curriculum_overrides",
    "pretrained_path",
    "train_command",
]

#: The training scenario of each policy: layout, navigator, tasks and robot count.
SCENARIOS: dict[str, list[str]] = {
    # The default scenario (60x60 shelves, A*, designated tasks): the demo's.
    "shelves_astar_m10": ["layout=shelves", "navigator=astar", "env.num_robots=10"],
    "open60_direct_m10": ["layout=open", "navigator=direct", "env.num_robots=10"],
    **{f"{p}_astar_m10": [f"layout={p}", "navigator=astar", "env.num_robots=10"] for p in "ABCDE"},
    "open60_direct_m100": ["layout=open", "navigator=direct", "env.num_robots=100"],
    # Table I's 100-robot rows.
    **{
        f"{p}_astar_m100": [f"layout={p}", "navigator=astar", "env.num_robots=100"]
        for p in "ABCDE"
    },
    # Scalability (Table II): large grids with random tasks spread over the whole grid.
    "open300_direct_m100_random": [
        "layout=open", "layout.width=300", "layout.height=300", "navigator=direct",
        "tasks=random", "env.num_robots=100",
    ],
    "C256_astar_m100_random": [
        "layout=C", "layout.width=256", "layout.height=256", "navigator=astar",
        "tasks=random", "env.num_robots=100",
    ],
}  # fmt: skip

#: The paper's network and RTAW+ get the same recipe and budget (docs/training.md): a
#: warm start imitating ``lookahead`` (65,536 labelled decisions, DAgger), then PPO.
_BUDGET = [
    "algo=ppo", "imitation.teacher=lookahead", "imitation.frames=65536", "frames=409600",
    "eval.every_frames=40960", "seed=0",
]  # fmt: skip
_RTAW = ["model=rtaw", *_BUDGET]
_RTAW_PLUS = ["model=rtaw_plus", *_BUDGET]

#: Table II's RTAW+ policies with 500 robots: a curriculum over ``M`` that continues the
#: best checkpoint of the 100-robot run (``runs/pretrained/<base>``, so train the base with
#: ``train_pretrained.py`` first) with 500 robots and 2,500-task episodes,
#: :data:`CURRICULUM_FRAMES` more PPO frames (``frames=`` counts from the base's best
#: checkpoint), selected on seeds 1000-1004. name -> (base entry, its best checkpoint's
#: frames).
CURRICULUM: dict[str, tuple[str, int]] = {
    "open300_direct_m500_random_plus": ("open300_direct_m100_random_plus", 368_640),
    "C256_astar_m500_random_plus": ("C256_astar_m100_random_plus", 409_600),
}
CURRICULUM_FRAMES = 163_840


def curriculum_overrides(name: str, base_checkpoint: str, base_frames: int) -> list[str]:
    """The overrides of :data:`CURRICULUM` entry ``name`` continuing ``base_checkpoint``
    (a checkpoint of its base's scenario after ``base_frames`` PPO frames) with 500
    robots for :data:`CURRICULUM_FRAMES` more frames. The registry's command continues
    ``runs/pretrained/<base>/checkpoints/best.pt``; ``experiments/seed_spread.py`` passes
    the best checkpoint of a base trained with another seed."""
    base = CURRICULUM[name][0]
    scenario = [o for o in SCENARIOS[base.removesuffix("_plus")] if "num_robots" not in o]
    return [
        *scenario, "env.num_robots=500", "env.num_tasks=2500", "model=rtaw_plus", "algo=ppo",
        f"frames={base_frames + CURRICULUM_FRAMES}", "eval.every_frames=40960",
        "eval.seeds=[1000,1001,1002,1003,1004]", "seed=0",
        f"resume={base_checkpoint}", "resume_new_scenario=true",
    ]  # fmt: skip


#: Table I's policies at three times the budget, both networks: the base run continued
#: from its ``last.pt`` (409,600 PPO frames) to :data:`LONG_FRAMES` with the same recipe,
#: in a copy of its folder ``runs/pretrained/<base>`` (so train the base first):
#: ``resume=<run_dir>/checkpoints/last.pt``. name -> base entry: ``<scenario>_long`` is
#: the paper's network, ``<scenario>_long_plus`` RTAW+.
LONG_FRAMES = 1_228_800
CONTINUED: dict[str, str] = {
    f"{scenario}_long{plus}": f"{scenario}{plus}"
    for m in (10, 100)
    for scenario in (f"open60_direct_m{m}", *(f"{p}_astar_m{m}" for p in "ABCDE"))
    for plus in ("", "_plus")
}


def _continued(base: str) -> list[str]:
    recipe = _RTAW_PLUS if base.endswith("_plus") else _RTAW
    budget = [o if not o.startswith("frames=") else f"frames={LONG_FRAMES}" for o in recipe]
    return [*SCENARIOS[base.removesuffix("_plus")], *budget]


#: name -> the rtaw-train overrides each checkpoint records (besides output_dir, progress):
#: ``<scenario>`` is the paper's network, ``<scenario>_plus`` RTAW+.
PRETRAINED: dict[str, list[str]] = {
    **{name: [*scenario, *_RTAW] for name, scenario in SCENARIOS.items()},
    **{f"{name}_plus": [*scenario, *_RTAW_PLUS] for name, scenario in SCENARIOS.items()},
    **{
        name: curriculum_overrides(name, f"runs/pretrained/{base}/checkpoints/best.pt", frames)
        for name, (base, frames) in CURRICULUM.items()
    },
    **{name: _continued(base) for name, base in CONTINUED.items()},
}


def train_command(name: str, run_dir: Path) -> list[str]:
    """The command that trains entry ``name`` into ``run_dir`` (for a :data:`CONTINUED`
    entry, ``run_dir`` must hold a copy of its base's run)."""
    if name not in PRETRAINED:
        raise unknown_name("pretrained policy", name, list(PRETRAINED))
    exe = str(Path(sys.executable).with_name("rtaw-train"))
    resume = [f"resume={run_dir}/checkpoints/last.pt"] if name in CONTINUED else []
    return [exe, *PRETRAINED[name], *resume, f"output_dir={run_dir}", "progress=false"]


def pretrained_path(name: str) -> Path:
    """The shipped checkpoint of entry ``name``.

    Raises:
        ConfigError: Unknown name (the message lists them) or the file is missing.
    """
    if name not in PRETRAINED:
        raise unknown_name("pretrained policy", name, list(PRETRAINED))
    path = Path(__file__).resolve().parent / f"{name}.pt"
    if not path.is_file():
        raise ConfigError(
            f"pretrained policy {name!r} is not shipped in this copy ({path} is missing); "
            f"train it with: python experiments/train_pretrained.py {name}"
        )
    return path
