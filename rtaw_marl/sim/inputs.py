"""Checks of the values a caller hands the simulator at run time: actions and seeds.

Both envs (the PettingZoo AEC env and the batched TorchRL env) pass user values through
these, so a bad action or seed fails the same way, with one clear message, whichever
route it takes: an :class:`~rtaw_marl.errors.InvalidActionError` for an action, a
:class:`~rtaw_marl.errors.ConfigError` for a seed.
"""

from __future__ import annotations

import operator
from collections import Counter
from collections.abc import Sequence

import numpy as np

from rtaw_marl.errors import ConfigError, InvalidActionError

__all__ = [
    "RESERVED_SEEDS",
    "SELECTION_SEEDS",
    "TRAINING_SEED_END",
    "draw_training_seed",
    "seed_list",
    "seed_span",
    "seed_value",
    "slot_index",
    "training_seed",
]

#: Episode seeds below this are reserved for results: evaluation (0-19, and the rest of
#: 0-999 for larger studies) and checkpoint selection (1000-1999). No training episode
#: ever uses one (:func:`training_seed`, :func:`draw_training_seed`).
RESERVED_SEEDS = 2000
#: The first checkpoint-selection seed (training's ``selection.seeds``); evaluation seeds
#: (``rtaw-eval``, the tables) lie below it.
SELECTION_SEEDS = 1000
#: Training episode seeds lie in ``RESERVED_SEEDS .. TRAINING_SEED_END - 1``.
TRAINING_SEED_END = 2**62


def _integer(value: object) -> int | None:
    """``value`` as an ``int`` if it is an integer scalar, else ``None``.

    Integer scalars are Python and NumPy integers and 0-d integer arrays or tensors; a
    bool (``True``, ``np.True_``, a bool array), a float (even ``1.0``), a string, and
    an array of any shape other than ``()`` are not.
    """
    if type(value) is int:  # the common case, first
        return value
    if isinstance(value, (bool, np.bool_)) or str(getattr(value, "dtype", "")) in (
        "bool",
        "torch.bool",
    ):
        return None
    if tuple(getattr(value, "shape", ())) != ():
        return None
    try:
        return operator.index(value)
    except TypeError:
        return None


def _describe(value: object) -> str:
    """``value`` for an error message: its repr and type (and shape, for an array)."""
    shape = getattr(value, "shape", None)
    kind = type(value).__name__
    if shape is not None and tuple(shape) != ():
        kind = f"{kind} of shape {tuple(shape)}"
    return f"{value!r} ({kind})"


def slot_index(action: object, queue_len: int) -> int:
    """The queue slot ``action`` names, checked against ``0 .. queue_len - 1``.

    Args:
        action: A Python or NumPy integer, or a 0-d integer array or tensor.
        queue_len: ``N``, the number of slots.

    Returns:
        The slot as a Python ``int``.

    Raises:
        InvalidActionError: ``action`` is not an integer scalar (a bool, a float even if
            integral, ``inf``, ``None``, a string, an array of shape other than ``()``),
            or it is out of range. Whether the slot holds a task is the caller's check.
    """
    slot = _integer(action)
    if slot is None:
        raise InvalidActionError(
            f"action must be an integer slot index in 0..{queue_len - 1}, got {_describe(action)}"
        )
    if not 0 <= slot < queue_len:
        raise InvalidActionError(f"action {slot} is not a queue slot (0..{queue_len - 1})")
    return slot


def seed_value(seed: object, name: str = "seed") -> int:
    """``seed`` as a Python ``int``, checked to be an integer ``>= 0``.

    Args:
        seed: A Python or NumPy integer (or a 0-d integer array or tensor).
        name: What the seed is called in the error message.

    Returns:
        The seed as a Python ``int``.

    Raises:
        ConfigError: ``seed`` is negative or not an integer (a bool, a float even if
            integral, a string, ...).
    """
    value = _integer(seed)
    if value is None or value < 0:
        raise ConfigError(f"{name} must be an integer >= 0, got {_describe(seed)}")
    return value


def seed_span(seeds: Sequence[int]) -> str:
    """Seeds for a line of text: ``0-19``, ``3, 5, 8``, ``0-9, 20-29``: runs of three or
    more consecutive seeds joined, in sorted order."""
    runs: list[list[int]] = []
    for seed in sorted(seeds):
        if runs and seed == runs[-1][-1] + 1:
            runs[-1].append(seed)
        else:
            runs.append([seed])
    return ", ".join(f"{r[0]}-{r[-1]}" if len(r) > 2 else ", ".join(map(str, r)) for r in runs)


def seed_list(seeds: object, name: str = "seeds") -> list[int]:
    """``seeds`` as a list of distinct Python integers ``>= 0``, in their order.

    A seed given twice would count one episode twice (and shrink a confidence interval
    it does not deserve), so duplicates are an error, not merged.

    Args:
        seeds: One integer, or a sequence of them.
        name: The config key, for the message.

    Raises:
        ConfigError: Empty, not integers, negative, or a seed given more than once.
    """
    items = [seeds] if _integer(seeds) is not None else seeds
    if isinstance(items, (str, bytes)) or not hasattr(items, "__iter__"):
        raise ConfigError(
            f"{name} must be a non-empty list of integers >= 0, got {_describe(seeds)}"
        )
    values = [seed_value(s, f"{name}[{i}]") for i, s in enumerate(items)]
    if not values:
        raise ConfigError(f"{name} must be a non-empty list of integers >= 0, got []")
    if len(set(values)) < len(values):
        counts = Counter(values)
        repeated = [f"{s} ({n} times)" for s, n in counts.items() if n > 1]
        raise ConfigError(
            f"{name} lists a seed more than once: {', '.join(repeated[:5])}"
            f"{' ...' if len(repeated) > 5 else ''}; each seed is one episode, list it once"
        )
    return values


def training_seed(seed: object, name: str = "seed") -> int:
    """The training episode seed that a run's ``seed`` (any integer ``>= 0``) stands
    for: ``RESERVED_SEEDS + seed`` (modulo the range), so ``seed=0`` is not evaluation
    seed 0's episode, distinct seeds give distinct episodes, and the result is never a
    reserved seed.

    Raises:
        ConfigError: ``seed`` is negative or not an integer.
    """
    span = TRAINING_SEED_END - RESERVED_SEEDS
    return RESERVED_SEEDS + seed_value(seed, name) % span


def draw_training_seed(rng: np.random.Generator) -> int:
    """An unseeded episode's seed, drawn from ``rng`` outside the reserved seeds."""
    return int(rng.integers(RESERVED_SEEDS, TRAINING_SEED_END))
