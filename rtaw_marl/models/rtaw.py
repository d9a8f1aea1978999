"""The paper's attention-inspired allocation network (section "Network Architecture").

Shapes use ``*`` for any batch dimensions, ``M`` robots, ``N`` queue slots and
``E = embed_dim`` (16 in the paper).

* Robot features ``[*, M, 3]`` -> Linear(3, E) -> ReLU -> Linear(E, E): embeddings
  ``E_j``; the selected robot's features ``[*, 3]`` go through the same layers: ``E_sel``.
* Task features ``[*, N, 6]`` -> Linear(6, E) -> ReLU -> Linear(E, E): embeddings ``E_i``.
* Gates ``alpha = sigmoid(Linear(E, 1)(tanh(Linear(E, E)(E))))`` per robot and per task.
* Summaries ``v_R = sum_j alpha_j E_j / sum_j alpha_j`` and likewise ``v_P`` over the
  *non-empty* task slots. The paper calls these "weighted averages"; normalising by the
  gate sum keeps their scale independent of ``M`` and ``N``, which is what lets a policy
  trained with 10 robots run with 1000.
* State ``V = (v_R, v_P, E_sel)`` ``[*, 3E]``, broadcast onto every task embedding:
  ``[*, N, 4E]`` -> Linear(4E, 8) -> ReLU -> Linear(8, 1): one logit per task.
  Empty slots are masked by the caller's ``MaskedCategorical``.

The critic (our design; the paper does not specify it) is a separate encoder of the same
form (its own embeddings and gates) whose state ``V`` goes through Linear(3E, 32) ->
Tanh -> Linear(32, 1). Separate parameters keep the value regression from disturbing the
policy's features, which matters with the paper's tiny value coefficient.

No layer size depends on ``M`` or ``N``.
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

__all__ = ["RTAWActor", "RTAWCritic", "RTAWEncoder"]


def _mlp(inp: int, hidden: int, out: int, act: type[nn.Module]) -> nn.Sequential:
    return nn.Sequential(nn.Linear(inp, hidden), act(), nn.Linear(hidden, out))


class RTAWEncoder(nn.Module):
    """Embeddings, gates and gated summaries of robots and tasks.

    Args:
        robot_dim: Robot feature size (3).
        task_dim: Task feature size (6).
        embed_dim: Embedding size ``E`` (16 in the paper).
    """

    def __init__(self, robot_dim: int, task_dim: int, embed_dim: int) -> None:
        super().__init__()
        self.robot_dim, self.task_dim, self.embed_dim = robot_dim, task_dim, embed_dim
        self.robot_embed = _mlp(robot_dim, embed_dim, embed_dim, nn.ReLU)
        self.task_embed = _mlp(task_dim, embed_dim, embed_dim, nn.ReLU)
        self.robot_gate = nn.Sequential(_mlp(embed_dim, embed_dim, 1, nn.Tanh), nn.Sigmoid())
        self.task_gate = nn.Sequential(_mlp(embed_dim, embed_dim, 1, nn.Tanh), nn.Sigmoid())

    def forward(
        self,
        robots: torch.Tensor,
        tasks: torch.Tensor,
        agent: torch.Tensor,
        action_mask: torch.Tensor,
    ) -> tuple[torch.Tensor, torch.Tensor]:
        """Encode a state.

        Args:
            robots: ``[*, M, 3]`` robot features.
            tasks: ``[*, N, 6]`` task features.
            agent: ``[*, 3]`` the selected robot's features.
            action_mask: ``[*, N]`` bool, non-empty slots.

        Returns:
            The state ``V`` ``[*, 3E]`` and the task embeddings ``[*, N, E]``.
        """
        robot_emb = self.robot_embed(robots)
        task_emb = self.task_embed(tasks)
        robot_w = self.robot_gate(robot_emb)
        task_w = self.task_gate(task_emb) * action_mask.unsqueeze(-1).to(task_emb.dtype)
        v_robots = (robot_w * robot_emb).sum(-2) / robot_w.sum(-2).clamp_min(1e-6)
        v_tasks = (task_w * task_emb).sum(-2) / task_w.sum(-2).clamp_min(1e-6)
        state = torch.cat([v_robots, v_tasks, self.robot_embed(agent)], dim=-1)
        return state, task_emb


class RTAWActor(nn.Module):
    """Logits over the queue slots ``[*, N]`` (the paper's policy network).

    Args:
        robot_dim: Robot feature size.
        task_dim: Task feature size.
        embed_dim: Embedding size ``E``.
        head_dim: Hidden size of the per-task scoring layer (8 in the paper).
    """

    in_keys = ("robots", "tasks", "agent", "action_mask")

    def __init__(self, robot_dim: int, task_dim: int, embed_dim: int, head_dim: int) -> None:
        super().__init__()
        self.encoder = RTAWEncoder(robot_dim, task_dim, embed_dim)
        self.head = _mlp(4 * embed_dim, head_dim, 1, nn.ReLU)

    def forward(
        self,
        robots: torch.Tensor,
        tasks: torch.Tensor,
        agent: torch.Tensor,
        action_mask: torch.Tensor,
    ) -> torch.Tensor:
        """Per-slot logits ``[*, N]`` (masking is left to the distribution)."""
        state, task_emb = self.encoder(robots, tasks, agent, action_mask)
        state = state.unsqueeze(-2).expand(*task_emb.shape[:-1], state.shape[-1])
        return self.head(torch.cat([state, task_emb], dim=-1)).squeeze(-1)


class RTAWCritic(nn.Module):
    """State value ``[*, 1]`` from a separate encoder's state ``V``.

    Args:
        robot_dim: Robot feature size.
        task_dim: Task feature size.
        embed_dim: Embedding size ``E``.
        hidden_dim: Hidden size of the value head.
    """

    in_keys = ("robots", "tasks", "agent", "action_mask")

    def __init__(self, robot_dim: int, task_dim: int, embed_dim: int, hidden_dim: int) -> None:
        super().__init__()
        self.encoder = RTAWEncoder(robot_dim, task_dim, embed_dim)
        self.head = _mlp(3 * embed_dim, hidden_dim, 1, nn.Tanh)

    def forward(
        self,
        robots: torch.Tensor,
        tasks: torch.Tensor,
        agent: torch.Tensor,
        action_mask: torch.Tensor,
    ) -> torch.Tensor:
        """Value ``[*, 1]``."""
        state, _ = self.encoder(robots, tasks, agent, action_mask)
        return self.head(state)
