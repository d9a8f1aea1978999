"""Your own policy, by value or by name: a plain function, or ``module:Name``.

Evaluation plays policies through their fast path ``act_sim(sim) -> slot``. A function
``choose(sim) -> int`` (the queue slot for ``sim.robot``, one of
``numpy.flatnonzero(sim.queue_mask)``) becomes such a policy with
:class:`CallablePolicy`; any object with ``act_sim`` and ``reset`` already is one.

On the command line ``policy=[mpdm,my_rules:Nearest]`` imports ``my_rules`` (from the
working directory or the installed packages) and takes its attribute ``Nearest``:

* an object with ``act_sim`` (a policy instance) is used as it is;
* a class is called without arguments and must give such an object;
* any other callable is a decision function, wrapped in :class:`CallablePolicy`.

Its label in tables is the attribute's name (``Nearest``).
"""

from __future__ import annotations

import importlib
import inspect
import os
import re
import sys
from collections.abc import Callable
from typing import Any

from rtaw_marl.errors import ConfigError
from rtaw_marl.sim.core import WarehouseSim

__all__ = ["CallablePolicy", "as_policy", "import_policy", "is_import_spec"]

#: ``package.module:Name``: a dotted module path, a colon, an attribute name.
_SPEC = re.compile(r"^[A-Za-z_]\w*(\.[A-Za-z_]\w*)*:[A-Za-z_]\w*$")


class CallablePolicy:
    """A decision function as a policy: ``act_sim(sim)`` is ``choose(sim)``.

    Args:
        choose: ``choose(sim) -> slot``: the queue slot for ``sim.robot``.
        name: Its label in tables; the function's ``__name__`` when ``None``.
    """

    def __init__(self, choose: Callable[[WarehouseSim], int], name: str | None = None) -> None:
        self.choose = choose
        self.name = name or getattr(choose, "__name__", "policy")

    def reset(self, seed: int | None = None) -> None:
        """A plain function keeps no state between episodes: nothing to reset."""

    def act_sim(self, sim: WarehouseSim) -> int:
        """The slot ``choose`` picks for ``sim``'s selected robot."""
        return int(self.choose(sim))


def as_policy(obj: Any, name: str | None = None) -> Any:
    """``obj`` as something evaluation can play: a policy as it is, a class built
    without arguments, a function wrapped in :class:`CallablePolicy`.

    Raises:
        ConfigError: ``obj`` is neither (the message names ``name``).
    """
    label = name or getattr(obj, "__name__", type(obj).__name__)
    if inspect.isclass(obj):
        try:
            obj = obj()
        except TypeError as exc:
            raise ConfigError(
                f"policy {label}: a class must build without arguments ({exc})"
            ) from None
    if hasattr(obj, "act_sim") and hasattr(obj, "reset"):
        return obj
    if callable(obj):
        return CallablePolicy(obj, name=label)
    raise ConfigError(
        f"policy {label} is a {type(obj).__name__}: expected a policy (act_sim and reset), "
        "a class that builds one, or a function choose(sim) -> slot"
    )


def is_import_spec(name: str) -> bool:
    """Whether ``name`` names a user policy (``module:Name``), not a registered rule."""
    return ":" in name


def import_policy(spec: str) -> tuple[str, Any]:
    """``(label, policy)`` for ``spec`` = ``module:Name`` (see the module docstring).

    Raises:
        ConfigError: A malformed spec, a module that cannot be imported, a missing
            attribute (the message lists the module's public callables), or an
            attribute that is no policy.
    """
    if not _SPEC.match(spec):
        raise ConfigError(
            f"policy {spec!r}: a user policy is named module:Name, e.g. my_rules:Nearest"
        )
    module_name, attribute = spec.split(":")
    try:
        module = _import_from_cwd(module_name)
    except ModuleNotFoundError as exc:
        missing = exc.name or ""
        if module_name == missing or module_name.startswith(missing + "."):
            raise ConfigError(
                f"policy {spec}: no module named {exc.name!r} (it is imported from the "
                "working directory or the installed packages)"
            ) from None
        raise ConfigError(f"policy {spec}: importing {module_name} failed: {exc}") from None
    if not hasattr(module, attribute):
        public = sorted(n for n, v in vars(module).items() if callable(v) and not n.startswith("_"))
        raise ConfigError(
            f"policy {spec}: {module_name} has no {attribute!r}; its callables: "
            f"{', '.join(public) or 'none'}"
        )
    return attribute, as_policy(getattr(module, attribute), name=attribute)


def _import_from_cwd(module_name: str) -> Any:
    """Import ``module_name``, looking in the working directory too: a console script's
    ``sys.path`` starts at its own folder, not where the user runs it. The working
    directory goes last, so it never shadows an installed package."""
    cwd = os.getcwd()
    if cwd in sys.path or "" in sys.path:
        return importlib.import_module(module_name)
    sys.path.append(cwd)
    try:
        return importlib.import_module(module_name)
    finally:
        sys.path.remove(cwd)
