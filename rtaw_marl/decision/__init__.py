"""The decision model: what a freed robot sees when it must choose a task.

The simulator stops whenever a robot is free and tasks are queued; that moment is one
*decision*. A :class:`Decision` holds the arrays it is observed from (the robots' cells
and times until free, the queue's slots, the distance model's distances), for one simulator
or a batch of them, and :func:`decision_features` turns it into the observation entries
(the paper's ``robots``, ``tasks``, ``agent``; RTAW+'s ``relations``, ``rivals``;
the critic's ``fleet``), whose shapes :func:`feature_shapes` writes once. Every reader
gets the same arrays, bit for bit, by one of two routes:

* from the simulator: :func:`sim_observation` and ``Decision.of_sim`` (the policies'
  ``act_sim`` fast path; with :func:`candidate_slots`, only the ``K`` slots nearest the
  free robot), or a ``Decision`` of ``B`` simulators' stacked arrays (the batched
  TorchRL env);
* from an env observation: the env adapters build it with :class:`AgentViews` (every
  agent's view, in an :class:`ObservationLayout`: ``full`` or ``compact``, ``dict`` or
  ``flat``), and a policy reads its features back with :func:`read_features`.

The hand-written rules decide from one :class:`RuleInput` (what the observation holds,
plus the distance model), built from the simulator or from an observation, so that each rule
is written once.

Modules: :mod:`~rtaw_marl.decision.features` (the one observation builder, with the
compiled rival kernels of ``_rivals``), :mod:`~rtaw_marl.decision.observations`
(observation layouts, every agent's view, the global state :func:`state_vector`) and
:mod:`~rtaw_marl.decision.rule_input` (the rules' input and its two builders).
This package needs NumPy and Numba only: it sits below the env adapters (which add the
Gymnasium spaces, :mod:`rtaw_marl.envs.spaces`), the models and the policies.
"""

from rtaw_marl.decision.features import (
    ALL_KEYS,
    FEATURES,
    FLEET_FEATURES,
    FLEET_QUANTILES,
    MISSING,
    NUM_RIVALS,
    OBSERVATION_KEYS,
    RELATION_FEATURES,
    RELATIONAL_KEYS,
    RIVAL_FEATURES,
    ROBOT_FEATURES,
    SOFTMIN_TEMPERATURE,
    TASK_FEATURES,
    Decision,
    candidate_slots,
    decision_features,
    feature_shapes,
    fleet_features,
    nearest_other,
    relational_features,
    robot_features,
    sim_observation,
    sim_relations,
    task_features,
)
from rtaw_marl.decision.observations import (
    FEATURE_KEYS,
    OBS_FORMATS,
    OBSERVATIONS,
    QUEUE_STATE_FEATURES,
    AgentViews,
    Features,
    ObservationLayout,
    read_features,
    state_vector,
)
from rtaw_marl.decision.rule_input import RULE_NEEDS, RuleInput, acting_row, free_times

__all__ = [
    "ALL_KEYS",
    "FEATURES",
    "FEATURE_KEYS",
    "FLEET_FEATURES",
    "FLEET_QUANTILES",
    "MISSING",
    "NUM_RIVALS",
    "OBSERVATIONS",
    "OBSERVATION_KEYS",
    "OBS_FORMATS",
    "QUEUE_STATE_FEATURES",
    "RELATIONAL_KEYS",
    "RELATION_FEATURES",
    "RIVAL_FEATURES",
    "ROBOT_FEATURES",
    "RULE_NEEDS",
    "SOFTMIN_TEMPERATURE",
    "TASK_FEATURES",
    "AgentViews",
    "Decision",
    "Features",
    "ObservationLayout",
    "RuleInput",
    "acting_row",
    "candidate_slots",
    "decision_features",
    "feature_shapes",
    "fleet_features",
    "free_times",
    "nearest_other",
    "read_features",
    "relational_features",
    "robot_features",
    "sim_observation",
    "sim_relations",
    "state_vector",
    "task_features",
]
