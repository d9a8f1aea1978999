"""RTAW+: size independent of M and N, invariant to robots, equivariant to tasks, masking."""

from __future__ import annotations

import pytest
import torch
from tensordict import TensorDict

from rtaw_marl.errors import ConfigError
from rtaw_marl.models.actor_critic import make_actor, make_critic
from rtaw_marl.models.checkpoint import build_networks
from rtaw_marl.models.config import RTAWPlusConfig

pytestmark = pytest.mark.unit


def _state(batch: int, m: int, n: int, seed: int = 0, k: int = 8) -> TensorDict:
    g = torch.Generator().manual_seed(seed)
    mask = torch.rand(batch, n, generator=g) > 0.3
    mask[:, 0] = True
    rivals = torch.rand(batch, n, k, 4, generator=g)
    rivals[..., 3] = (torch.rand(batch, n, k, generator=g) > 0.2).float()
    return TensorDict(
        {
            "relations": torch.rand(batch, n, 8, generator=g) * mask.unsqueeze(-1),
            "rivals": rivals * mask[..., None, None],
            "robots": torch.rand(batch, m, 3, generator=g),
            "action_mask": mask,
        },
        batch_size=[batch],
    )


def _run(actor, critic, td: TensorDict) -> tuple[torch.Tensor, torch.Tensor]:
    return (
        actor(*(td[k] for k in actor.in_keys)),
        critic(*(td[k] for k in critic.in_keys)),
    )


def test_parameter_count_is_independent_of_m_and_n() -> None:
    torch.manual_seed(0)
    actor, critic = build_networks(RTAWPlusConfig())
    sizes = {sum(p.numel() for p in (*actor.parameters(), *critic.parameters()))}
    for m, n in [(10, 10), (100, 2), (1000, 50)]:
        logits, value = _run(actor, critic, _state(2, m, n))
        assert logits.shape == (2, n)
        assert value.shape == (2, 1)
        sizes.add(sum(p.numel() for p in (*actor.parameters(), *critic.parameters())))
    assert len(sizes) == 1


def test_permuting_rivals_and_robots_leaves_outputs_unchanged() -> None:
    torch.manual_seed(1)
    actor, critic = build_networks(RTAWPlusConfig())
    td = _state(3, 12, 7)
    shuffled = td.clone()
    shuffled["rivals"] = td["rivals"][:, :, torch.randperm(8)]
    shuffled["robots"] = td["robots"][:, torch.randperm(12)]
    for a, b in zip(_run(actor, critic, td), _run(actor, critic, shuffled), strict=True):
        torch.testing.assert_close(a, b)


def test_permuting_tasks_permutes_logits() -> None:
    torch.manual_seed(2)
    actor, critic = build_networks(RTAWPlusConfig())
    td = _state(3, 5, 9)
    perm = torch.randperm(9)
    shuffled = td.clone()
    for key in ("relations", "rivals", "action_mask"):
        shuffled[key] = td[key][:, perm]
    logits, value = _run(actor, critic, td)
    logits_p, value_p = _run(actor, critic, shuffled)
    torch.testing.assert_close(logits[:, perm], logits_p)
    torch.testing.assert_close(value, value_p)


def test_empty_slots_and_invalid_rivals_do_not_matter() -> None:
    """Appending masked slots, or changing the values of invalid rival rows, leaves the
    logits of the real tasks and the value unchanged."""
    torch.manual_seed(3)
    actor, critic = build_networks(RTAWPlusConfig())
    td = _state(2, 4, 3)
    td["action_mask"][:] = True
    padded = td.clone()
    padded["relations"] = torch.cat([td["relations"], torch.rand(2, 4, 8)], dim=1)
    padded["rivals"] = torch.cat([td["rivals"], torch.rand(2, 4, 8, 4)], dim=1)
    padded["action_mask"] = torch.cat([td["action_mask"], torch.zeros(2, 4, dtype=torch.bool)], 1)
    logits, value = _run(actor, critic, td)
    logits_p, value_p = _run(actor, critic, padded)
    torch.testing.assert_close(logits, logits_p[:, :3])
    torch.testing.assert_close(value, value_p)
    noisy = td.clone()
    invalid = noisy["rivals"][..., 3] == 0
    noisy["rivals"][..., :3][invalid] = 5.0
    torch.testing.assert_close(actor(*(td[k] for k in actor.in_keys)),
                               actor(*(noisy[k] for k in actor.in_keys)))  # fmt: skip


def test_no_rivals_and_no_tasks_stay_finite() -> None:
    """One robot (every rival row invalid) and an all-empty queue (the state after a
    drain episode's last decision) give finite outputs, no NaN."""
    actor, critic = build_networks(RTAWPlusConfig())
    td = _state(2, 1, 4)
    td["rivals"][..., 3] = 0.0
    td["action_mask"][1] = False
    logits, value = _run(actor, critic, td)
    assert torch.isfinite(logits).all()
    assert torch.isfinite(value).all()


def test_torchrl_wrappers_sample_valid_slots() -> None:
    torch.manual_seed(4)
    actor_net, critic_net = build_networks(RTAWPlusConfig())
    actor, critic = make_actor(actor_net), make_critic(critic_net)
    td = _state(64, 6, 8, seed=5)
    out = actor(td.clone())
    assert td["action_mask"].gather(1, out["action"].unsqueeze(1)).all()
    assert critic(td.clone())["state_value"].shape == (64, 1)


@pytest.mark.parametrize(
    ("keys", "match"),
    [({"heads": 3}, "multiple"), ({"embed_dim": 0}, "embed_dim"), ({"name": "rtaw"}, "name")],
)
def test_bad_config_is_an_error(keys: dict, match: str) -> None:
    with pytest.raises(ConfigError, match=match):
        RTAWPlusConfig(**keys)


def test_critic_without_the_fleet_does_not_read_the_robots() -> None:
    """``critic_fleet=false`` (the ablation): the value depends on the tasks' relational
    view only; the actor is the same network."""
    torch.manual_seed(6)
    actor, critic = build_networks(RTAWPlusConfig(critic_fleet=False))
    assert critic.in_keys == ("relations", "action_mask")
    assert actor.in_keys == build_networks(RTAWPlusConfig())[0].in_keys
    td = _state(4, 9, 6, seed=7)
    other = td.clone()
    other["robots"] = torch.rand(4, 30, 3)  # another fleet, another size
    value = critic(*(td[k] for k in critic.in_keys))
    torch.testing.assert_close(value, critic(*(other[k] for k in critic.in_keys)))
    assert make_critic(critic)(td.clone())["state_value"].shape == (4, 1)
    # The full critic does read them.
    full = build_networks(RTAWPlusConfig())[1]
    assert not torch.allclose(
        full(*(td[k] for k in full.in_keys)), full(*(other[k] for k in full.in_keys))
    )


def test_fleet_summary_critic_reads_a_fixed_size_fleet() -> None:
    torch.manual_seed(0)
    actor, critic = build_networks(RTAWPlusConfig(fleet_summary=True))
    assert critic.in_keys == ("relations", "fleet", "action_mask")
    assert actor.in_keys == ("relations", "rivals", "action_mask")
    td = _state(4, 5, 6)
    fleet = torch.rand(4, 8)
    value = critic(td["relations"], fleet, td["action_mask"])
    assert value.shape == (4, 1)
    # The fleet summary moves the value (it is read, not ignored).
    assert not torch.equal(value, critic(td["relations"], fleet * 3.0, td["action_mask"]))


def test_fleet_summary_needs_a_critic_that_sees_the_fleet() -> None:
    with pytest.raises(ConfigError, match=r"model\.critic_fleet=false shows it none"):
        RTAWPlusConfig(fleet_summary=True, critic_fleet=False)
    with pytest.raises(ConfigError, match=r"model\.fleet_summary must be true or false"):
        RTAWPlusConfig(fleet_summary="yes")
