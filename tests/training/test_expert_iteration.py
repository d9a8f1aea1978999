"""Expert iteration: ``imitation.teacher=search`` labels with the search over the
network being trained (a frozen copy per round), or over a fixed policy."""

from __future__ import annotations

import pytest
import torch

from rtaw_marl.errors import ConfigError
from rtaw_marl.models.checkpoint import build_networks
from rtaw_marl.models.config import RTAWPlusConfig
from rtaw_marl.policies.config import SearchConfig
from rtaw_marl.policies.network import load_policy
from rtaw_marl.sim.builder import SimSpec
from rtaw_marl.training.config import ImitationConfig
from rtaw_marl.training.imitation import _search_teacher, imitate
from tests.training.conftest import POC_LAYOUT, POC_SIM

pytestmark = pytest.mark.integration


def test_the_search_teacher_is_a_frozen_copy_of_the_network() -> None:
    actor, critic = build_networks(RTAWPlusConfig())
    teacher = _search_teacher(SearchConfig(width=3, horizon=2), actor, critic, None)
    assert teacher.network.net is not actor
    assert teacher.critic is None  # leaf = 0: no critic needed
    with torch.no_grad():
        next(actor.parameters()).add_(1.0)  # the round's fit moves the actor ...
    frozen = dict(teacher.network.net.named_parameters())
    moved = dict(actor.named_parameters())
    assert not torch.equal(frozen[next(iter(frozen))], moved[next(iter(moved))])  # ... not it
    valued = _search_teacher(SearchConfig(leaf=0.5), actor, critic, 0.1)
    assert valued.critic is not None
    assert valued.critic is not critic
    assert valued.reward_scale == 0.1


def test_a_fixed_search_policy_is_loaded() -> None:
    actor, critic = build_networks(RTAWPlusConfig())
    fixed = SearchConfig(policy="shelves_astar_m10_plus", width=2, horizon=1)
    teacher = _search_teacher(fixed, actor, critic, None)
    shipped = load_policy("shelves_astar_m10_plus").net.state_dict()
    assert all(torch.equal(v, teacher.network.net.state_dict()[k]) for k, v in shipped.items())
    assert (teacher.width, teacher.horizon) == (2, 1)


def test_expert_iteration_rounds_label_with_the_search() -> None:
    """Each round is labelled by the search; rounds after the first follow the student,
    whose agreement with its own search is measured (below 1: the search disagrees)."""
    torch.manual_seed(0)
    actor, critic = build_networks(RTAWPlusConfig())
    spec = SimSpec.of(POC_SIM, POC_LAYOUT, "direct", "poc")
    cfg = ImitationConfig(teacher="search", frames=96, rounds=3, epochs=1, minibatch_size=16,
                          search=SearchConfig(width=2, horizon=2))  # fmt: skip
    rows = imitate(cfg, spec, actor, critic, num_envs=4, seed=5, gamma=0.99, reward_scale=0.1)
    assert [r["round"] for r in rows] == [0, 1, 2]
    assert [r["decisions"] for r in rows] == [32, 64, 96]
    assert all(0.0 <= r["agreement"] <= 1.0 for r in rows[1:])


def test_search_is_a_teacher_and_its_options_are_checked() -> None:
    assert ImitationConfig(teacher="search").search == SearchConfig()
    with pytest.raises(ConfigError, match=r"imitation\.teacher must be one of .*, search or"):
        ImitationConfig(teacher="mcts")
    with pytest.raises(ConfigError, match=r"search\.width"):
        ImitationConfig(teacher="search", search=SearchConfig(width=0))
