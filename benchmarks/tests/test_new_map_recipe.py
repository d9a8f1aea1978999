"""The new-map measurement: its commands are the recipe as a user types it, and its table
is computed from the stored episodes."""

from __future__ import annotations

import pytest

from benchmarks.scripts import new_map_recipe as nm
from rtaw_marl.config import compose, to_typed

pytestmark = pytest.mark.unit


@pytest.mark.parametrize("name", list(nm.MAPS))
def test_the_commands_compose_the_recipe_on_the_map(name: str) -> None:
    train = nm.train_command(name)
    assert train[:2] == ["rtaw-train", "recipe=new_map"]
    if not (nm.SHARED / nm.MAPS[name][0]).exists():
        pytest.skip("../shared/maps is not here")
    cfg = to_typed(compose("train", train[1:]))
    assert cfg.init_actor == "generalist_plus"
    assert cfg.imitation.teacher == "best"
    assert cfg.sim.num_robots == nm.MAPS[name][1]
    assert cfg.layout.path.endswith(nm.MAPS[name][0])
    search = nm.search_command(name)
    assert f"search.policy={nm.RUNS / name / 'checkpoints' / 'best.pt'}" in search


def test_the_table_is_the_paired_differences_of_the_stored_episodes() -> None:
    stored = {
        "m": {
            "map": "movingai/x.map", "robots": 20, "seconds": 425, "best_rule": "hungarian",
            "recipe": "m/best", "verdict": {"outcome": "beats"},
            "ttd": {
                "hungarian": [100.0, 110.0, 120.0], "generalist_plus": [104.0, 113.0, 126.0],
                "m/best": [95.0, 104.0, 115.0], "searched": [99.0, 111.0, 119.0],
            },
        }
    }  # fmt: skip
    row = nm.render(stored).splitlines()[-1]
    cells = [c.strip() for c in row.strip("|").split("|")]
    assert cells[0] == "`x`, M=20"
    assert cells[1] == "hungarian"
    assert cells[2] == "105"
    assert cells[3].startswith("-3.9% [")  # (110 - 114.3) / 110
    assert cells[4].startswith("+4.8% [")  # (110 - 104.7) / 110
    assert cells[5] == "beats"
    assert cells[6].startswith("+0.3% [")
    assert cells[7] == "7.1 min"
