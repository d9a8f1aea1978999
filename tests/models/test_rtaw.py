"""The RTAW network: size independent of M and N, symmetric in robots and tasks, masking."""

from __future__ import annotations

import pytest
import torch
from tensordict import TensorDict

from rtaw_marl.models.actor_critic import make_actor, make_critic
from rtaw_marl.models.checkpoint import build_networks
from rtaw_marl.models.config import RTAWConfig

pytestmark = pytest.mark.unit


def _state(batch: int, m: int, n: int, seed: int = 0) -> TensorDict:
    g = torch.Generator().manual_seed(seed)
    mask = torch.rand(batch, n, generator=g) > 0.3
    mask[:, 0] = True
    return TensorDict(
        {
            "robots": torch.rand(batch, m, 3, generator=g),
            "tasks": torch.rand(batch, n, 6, generator=g) * mask.unsqueeze(-1),
            "agent": torch.rand(batch, 3, generator=g),
            "action_mask": mask,
        },
        batch_size=[batch],
    )


def _args(td: TensorDict) -> tuple[torch.Tensor, ...]:
    return td["robots"], td["tasks"], td["agent"], td["action_mask"]


def test_parameter_count_is_independent_of_m_and_n() -> None:
    """One network runs with 10, 100 and 1000 robots and 2..100 tasks; its size is fixed."""
    torch.manual_seed(0)
    actor, critic = build_networks(RTAWConfig())
    sizes = {sum(p.numel() for p in actor.parameters())}
    for m, n in [(10, 10), (100, 2), (1000, 100)]:
        td = _state(2, m, n)
        assert actor(*_args(td)).shape == (2, n)
        assert critic(*_args(td)).shape == (2, 1)
        sizes.add(sum(p.numel() for p in actor.parameters()))
    # 3->16->16 and 6->16->16 embeddings, two 16->16->1 gates, 64->8->1 head.
    assert sizes == {
        (3 * 16 + 16 + 16 * 16 + 16)
        + (6 * 16 + 16 + 16 * 16 + 16)
        + 2 * (16 * 16 + 16 + 16 + 1)
        + (64 * 8 + 8 + 8 + 1)
    }


def test_permuting_robots_leaves_output_unchanged() -> None:
    torch.manual_seed(1)
    actor, critic = build_networks(RTAWConfig())
    td = _state(3, 12, 7)
    perm = torch.randperm(12)
    shuffled = td.clone()
    shuffled["robots"] = td["robots"][:, perm]
    torch.testing.assert_close(actor(*_args(td)), actor(*_args(shuffled)))
    torch.testing.assert_close(critic(*_args(td)), critic(*_args(shuffled)))


def test_permuting_tasks_permutes_logits() -> None:
    torch.manual_seed(2)
    actor, critic = build_networks(RTAWConfig())
    td = _state(3, 5, 9)
    perm = torch.randperm(9)
    shuffled = td.clone()
    shuffled["tasks"] = td["tasks"][:, perm]
    shuffled["action_mask"] = td["action_mask"][:, perm]
    torch.testing.assert_close(actor(*_args(td))[:, perm], actor(*_args(shuffled)))
    torch.testing.assert_close(critic(*_args(td)), critic(*_args(shuffled)))


def test_empty_slots_do_not_change_the_valid_logits() -> None:
    """Appending masked slots leaves the logits of the real tasks unchanged."""
    torch.manual_seed(3)
    actor = build_networks(RTAWConfig())[0]
    td = _state(2, 4, 3)
    td["action_mask"][:] = True
    padded = TensorDict(
        {
            "robots": td["robots"],
            "tasks": torch.cat([td["tasks"], torch.zeros(2, 4, 6)], dim=1),
            "agent": td["agent"],
            "action_mask": torch.cat([td["action_mask"], torch.zeros(2, 4, dtype=torch.bool)], 1),
        },
        batch_size=[2],
    )
    torch.testing.assert_close(actor(*_args(td)), actor(*_args(padded))[:, :3])


def test_masked_tasks_get_probability_zero() -> None:
    torch.manual_seed(4)
    actor = make_actor(build_networks(RTAWConfig())[0])
    td = _state(64, 6, 8, seed=5)
    out = actor(td.clone())
    dist = actor.get_dist(td.clone())
    probs = dist.probs
    assert torch.all(probs[~td["action_mask"]] == 0)
    torch.testing.assert_close(probs.sum(-1), torch.ones(64))
    assert td["action_mask"].gather(1, out["action"].unsqueeze(1)).all()
    assert torch.isfinite(out["action_log_prob"]).all()


def test_critic_wrapper_writes_state_value() -> None:
    critic = make_critic(build_networks(RTAWConfig())[1])
    out = critic(_state(4, 3, 5))
    assert out["state_value"].shape == (4, 1)


@pytest.mark.parametrize("m", [1, 1000])
def test_single_robot_and_many_robots(m: int) -> None:
    actor = build_networks(RTAWConfig())[0]
    logits = actor(*_args(_state(1, m, 1)))
    assert logits.shape == (1, 1)
    assert torch.isfinite(logits).all()
