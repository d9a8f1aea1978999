"""RTAW+: a relational attention network (beyond the paper; ``model=rtaw_plus``).

The paper's network sees coordinates and must learn distances and competition between
robots itself. RTAW+ reads the relational features of :mod:`rtaw_marl.decision.features`
instead, and lets each queued task look at the robots that compete for it and at the
other tasks. Shapes: ``*`` batch dimensions, ``N`` queue slots, ``K = NUM_RIVALS`` rival
tokens per task, ``M`` robots (critic only), ``E = embed_dim``, ``H = heads``.

* Task tokens: ``relations [*, N, 8]`` -> Linear -> ReLU -> Linear -> ``[*, N, E]``.
* Cross-attention, task -> its rivals: each task queries its own ``K`` rival tokens
  (``rivals [*, N, K, 4]``: arrival minus the actor's, time until free, distance,
  valid) with ``H`` heads; keys and values (16 wide) come from Linear(4, 16) -> ReLU ->
  Linear(16, 32); invalid rivals are masked; Linear(16, E) back. Pre-norm, residual.
* Self-attention among the queued tasks (empty slots masked as keys), residual, then a
  feed-forward block (E -> 2E -> E): a task's score can depend on what else is queued.
* Head: Linear(E, E) -> ReLU -> Linear(E, 1): one logit per slot.

Every attention is a masked softmax over a set, and every layer acts per token, so the
network is invariant to the order of robots and equivariant to the order of tasks, and
no layer size depends on ``M`` or ``N``.

The critic has its own encoder of the same form without the rival attention (the
``N * K`` rival tokens are most of the cost, and the relations already summarise the
rivals) and, since it is only used in training, sees the whole fleet instead: the
robots' paper features ``[*, M, 3]`` are embedded and mean-pooled (or, with
``model.fleet_summary``, the fixed-size ``fleet [*, 8]`` is embedded); the masked mean of
the task tokens and the fleet summary go through Linear(2E, hidden) -> Tanh ->
Linear(hidden, 1).
"""

from __future__ import annotations

from rtaw_marl.errors import missing_extra

# Without the training extra: one error that names it (errors.missing_extra), no traceback
# of a bare ModuleNotFoundError.
try:
    import torch
    from torch import nn
except ModuleNotFoundError as exc:
    raise missing_extra(exc, __name__, "train") from None

from rtaw_marl.decision.features import (
    FLEET_FEATURES,
    RELATION_FEATURES,
    RIVAL_FEATURES,
    ROBOT_FEATURES,
)
from rtaw_marl.models.config import RIVAL_DIM

__all__ = ["RTAWPlusActor", "RTAWPlusCritic", "RTAWPlusEncoder"]

#: Large negative score of masked keys: finite, so a row with no valid key gives zeros
#: (after the validity factor) rather than NaN.
_MASKED = -1.0e9


def _mlp(inp: int, hidden: int, out: int) -> nn.Sequential:
    return nn.Sequential(nn.Linear(inp, hidden), nn.ReLU(), nn.Linear(hidden, out))


def _heads(x: torch.Tensor, heads: int) -> torch.Tensor:
    return x.unflatten(-1, (heads, x.shape[-1] // heads))


def _masked_softmax(scores: torch.Tensor, valid: torch.Tensor, dim: int) -> torch.Tensor:
    # Spelled out: torch.softmax over 8-10 entries runs at a tenth of the speed of
    # these four elementwise passes on a CPU (forward and backward).
    scores = scores.masked_fill(~valid, _MASKED)
    weights = (scores - scores.amax(dim, keepdim=True)).exp()
    return weights * (valid.to(weights.dtype) / weights.sum(dim, keepdim=True))


class _RivalAttention(nn.Module):
    """Each task attends to its own ``K`` rival tokens with ``H`` heads.

    Keys and values (``RIVAL_DIM`` wide, split over the heads) come straight from the
    rival features through one small MLP (``4 -> 16 -> 2 * RIVAL_DIM``): the ``N * K``
    rival tokens dominate the cost, so they get no wider embedding.
    """

    def __init__(self, dim: int, heads: int) -> None:
        super().__init__()
        if RIVAL_DIM % heads:
            raise ValueError(f"heads={heads} must divide the rival width {RIVAL_DIM}")
        self.heads = heads
        self.norm = nn.LayerNorm(dim)
        self.query = nn.Linear(dim, RIVAL_DIM)
        self.key_value = _mlp(len(RIVAL_FEATURES), 16, 2 * RIVAL_DIM)
        self.out = nn.Linear(RIVAL_DIM, dim)

    def forward(self, tasks: torch.Tensor, rivals: torch.Tensor) -> torch.Tensor:
        """``tasks [*, N, E]``, ``rivals [*, N, K, 4]`` -> ``[*, N, E]`` (residual added)."""
        h = self.heads
        q = _heads(self.query(self.norm(tasks)), h).unsqueeze(-3)  # [*, N, 1, H, d]
        k, v = (_heads(x, h) for x in self.key_value(rivals).chunk(2, dim=-1))  # [*, N, K, H, d]
        # Products and sums over d = 4, not einsum: its batched matrix products of 1 x 4
        # by 4 x K cost 4x more on a CPU (training's learner); the same function.
        scores = (q * k).sum(-1) / q.shape[-1] ** 0.5  # [*, N, K, H]
        valid = (rivals[..., -1] > 0.5).unsqueeze(-1)  # [*, N, K, 1]
        weights = _masked_softmax(scores, valid, dim=-2)  # over the K rivals
        mixed = (weights.unsqueeze(-1) * v).sum(-3)  # [*, N, H, d]
        return tasks + self.out(mixed.flatten(-2))


class _TaskAttention(nn.Module):
    """Self-attention among the queued tasks (empty slots masked as keys), residual."""

    def __init__(self, dim: int, heads: int) -> None:
        super().__init__()
        self.heads = heads
        self.norm = nn.LayerNorm(dim)
        self.qkv = nn.Linear(dim, 3 * dim)
        self.out = nn.Linear(dim, dim)

    def forward(self, tasks: torch.Tensor, action_mask: torch.Tensor) -> torch.Tensor:
        """``tasks [*, N, E]``, ``action_mask [*, N]`` -> ``[*, N, E]``."""
        q, k, v = (_heads(x, self.heads) for x in self.qkv(self.norm(tasks)).chunk(3, dim=-1))
        scores = torch.einsum("...qhd,...khd->...hqk", q, k) / q.shape[-1] ** 0.5
        valid = action_mask[..., None, None, :]  # [*, 1, 1, N]: keys
        weights = _masked_softmax(scores, valid, dim=-1)
        mixed = torch.einsum("...hqk,...khd->...qhd", weights, v)
        return tasks + self.out(mixed.flatten(-2))


class _FeedForward(nn.Module):
    def __init__(self, dim: int) -> None:
        super().__init__()
        self.norm = nn.LayerNorm(dim)
        self.mlp = _mlp(dim, 2 * dim, dim)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return x + self.mlp(self.norm(x))


class RTAWPlusEncoder(nn.Module):
    """Task tokens ``[*, N, E]``, optionally after rival cross-attention, then task
    self-attention.

    Args:
        embed_dim: ``E``.
        heads: ``H`` (divides ``E``).
        rivals: Attend to the rival tokens (the actor does; the critic sees the fleet
            instead).
    """

    def __init__(self, embed_dim: int, heads: int, rivals: bool) -> None:
        super().__init__()
        self.task_embed = _mlp(len(RELATION_FEATURES), embed_dim, embed_dim)
        self.cross = _RivalAttention(embed_dim, heads) if rivals else None
        self.self_attn = _TaskAttention(embed_dim, heads)
        self.ff = _FeedForward(embed_dim)

    def forward(
        self,
        relations: torch.Tensor,
        rivals: torch.Tensor | None,
        action_mask: torch.Tensor,
    ) -> torch.Tensor:
        """Encode a decision.

        Args:
            relations: ``[*, N, 8]`` relational task features.
            rivals: ``[*, N, K, 4]`` rival tokens (last column: valid), or ``None``
                for an encoder built without rivals.
            action_mask: ``[*, N]`` bool, non-empty slots.

        Returns:
            ``[*, N, E]`` task tokens.
        """
        tasks = self.task_embed(relations)
        if self.cross is not None:
            tasks = self.cross(tasks, rivals)
        return self.ff(self.self_attn(tasks, action_mask))


class RTAWPlusActor(nn.Module):
    """Logits over the queue slots ``[*, N]``.

    Args:
        embed_dim: ``E``.
        heads: Attention heads.
    """

    in_keys = ("relations", "rivals", "action_mask")

    def __init__(self, embed_dim: int, heads: int) -> None:
        super().__init__()
        if embed_dim % heads:
            raise ValueError(f"embed_dim={embed_dim} must be a multiple of heads={heads}")
        self.encoder = RTAWPlusEncoder(embed_dim, heads, rivals=True)
        self.head = _mlp(embed_dim, embed_dim, 1)

    def forward(
        self, relations: torch.Tensor, rivals: torch.Tensor, action_mask: torch.Tensor
    ) -> torch.Tensor:
        """Per-slot logits ``[*, N]`` (masking is left to the distribution)."""
        return self.head(self.encoder(relations, rivals, action_mask)).squeeze(-1)


class RTAWPlusCritic(nn.Module):
    """State value ``[*, 1]`` from its own task encoder and a whole-fleet summary.

    Args:
        embed_dim: ``E``.
        heads: Attention heads.
        hidden_dim: Hidden size of the value head.
        fleet: Also see the whole fleet (``robots``); ``False``: the tasks' relational
            view only, and ``in_keys`` drops ``robots``.
        summary: See the fleet as its fixed-size summary ``fleet [*, 8]``
            (``in_keys`` has ``fleet`` instead of ``robots``), embedded as one token.
    """

    in_keys: tuple[str, ...] = ("relations", "robots", "action_mask")

    def __init__(
        self, embed_dim: int, heads: int, hidden_dim: int, fleet: bool = True,
        *, summary: bool = False,
    ) -> None:  # fmt: skip
        super().__init__()
        self.encoder = RTAWPlusEncoder(embed_dim, heads, rivals=False)
        self.summary = fleet and summary
        width_in = len(FLEET_FEATURES) if self.summary else len(ROBOT_FEATURES)
        self.fleet_embed = _mlp(width_in, embed_dim, embed_dim) if fleet else None
        if not fleet:
            self.in_keys = ("relations", "action_mask")
        elif self.summary:
            self.in_keys = ("relations", "fleet", "action_mask")
        width = (2 if fleet else 1) * embed_dim
        self.head = nn.Sequential(nn.Linear(width, hidden_dim), nn.Tanh(), nn.Linear(hidden_dim, 1))

    def forward(self, relations: torch.Tensor, *rest: torch.Tensor) -> torch.Tensor:
        """Value ``[*, 1]`` from ``relations``, the fleet (``robots [*, M, 3]`` or
        ``fleet [*, 8]``, if it sees one) and ``action_mask``, in ``in_keys`` order."""
        *fleet, action_mask = rest
        tasks = self.encoder(relations, None, action_mask)
        weight = action_mask.unsqueeze(-1).to(tasks.dtype)
        parts = [(tasks * weight).sum(-2) / weight.sum(-2).clamp_min(1.0)]
        if self.fleet_embed is not None:
            embedded = self.fleet_embed(fleet[0])
            parts.append(embedded if self.summary else embedded.mean(-2))
        return self.head(torch.cat(parts, dim=-1))
