"""Shell completion of the Hydra commands: Hydra's own, checked and narrowed.

``rtaw-eval -sc install=bash`` prints Hydra's bash script (``zsh`` and ``fish`` too);
on every Tab the script runs ``rtaw-eval -sc query=bash`` with the line typed so far.
Two things are added here:

* the request is checked first: ``--shell-completion`` without ``install=``,
  ``uninstall=`` or ``query=``, or with an unknown shell, is one ``error:`` line (exit
  status 2) instead of Hydra's ``ValueError`` traceback;
* a query's answers leave out the config groups the command does not take (Hydra offers
  every group of the search path: ``algo=`` to ``rtaw-eval``, the internal ``schema/``),
  the same groups its ``--help`` leaves out (:func:`rtaw_marl.config.help.app_groups`).
"""

from __future__ import annotations

import contextlib
import io
import re
from collections.abc import Iterator, Sequence

from hydra.core.config_store import ConfigStore

from rtaw_marl.config import CONF_DIR
from rtaw_marl.config.help import app_groups
from rtaw_marl.errors import ConfigError, unknown_name

__all__ = ["SHELLS", "completion_request", "narrowed_completion", "own_words"]

#: The shells Hydra writes a completion script for.
SHELLS = ("bash", "fish", "zsh")

_FLAGS = ("-sc", "--shell-completion")
_SUBCOMMANDS = ("install", "uninstall", "query")


def completion_request(app: str, argv: Sequence[str]) -> str | None:
    """``install``, ``uninstall`` or ``query`` when ``argv`` asks for shell completion,
    else ``None``.

    Raises:
        ConfigError: Not exactly one of the three, or a shell Hydra has no script for.
    """
    if not any(arg in _FLAGS for arg in argv):
        return None
    given = [arg.partition("=") for arg in argv]
    requests = [(key, shell) for key, sep, shell in given if sep and key in _SUBCOMMANDS]
    if len(requests) != 1:
        raise ConfigError(
            "--shell-completion needs one of install=SHELL, uninstall=SHELL or query=SHELL "
            f'(SHELL: {", ".join(SHELLS)}), e.g. eval "$(rtaw-{app} -sc install=bash)"'
        )
    subcommand, shell = requests[0]
    if shell not in SHELLS:
        raise unknown_name("shell", shell, SHELLS)
    return subcommand


@contextlib.contextmanager
def narrowed_completion(app: str, argv: Sequence[str]) -> Iterator[None]:
    """Run Hydra's main inside: checks a completion request (:func:`completion_request`)
    and, for a query, prints only :func:`own_words` of what Hydra answers."""
    if completion_request(app, argv) != "query":
        yield
        return
    answer = io.StringIO()
    with contextlib.redirect_stdout(answer):
        yield
    text = answer.getvalue()
    # bash and zsh read the words from one line, fish one per line.
    separator = "\n" if "\n" in text.strip() else " "
    print(separator.join(own_words(app, text.split())))


def own_words(app: str, words: Sequence[str]) -> list[str]:
    """``words`` without those naming a config group ``app`` does not take
    (``algo=``, ``+zoo=``, ``schema/`` for ``rtaw-eval``)."""
    foreign = _all_groups() - set(app_groups(app)) - {"hydra"}
    return [w for w in words if re.split(r"[=/.]", w.lstrip("+~"), maxsplit=1)[0] not in foreign]


def _all_groups() -> set[str]:
    """Every top-level config group: the packaged folders and the ConfigStore's."""
    folders = {p.name for p in CONF_DIR.iterdir() if p.is_dir() and not p.name.startswith("_")}
    stored = {name for name in ConfigStore.instance().list("") if not name.endswith(".yaml")}
    return folders | stored
