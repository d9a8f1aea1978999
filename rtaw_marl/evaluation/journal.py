"""Finished episodes on disk as they finish, so a killed evaluation loses none of them.

``rtaw-eval`` writes ``results.json`` once, at the end. Beside it, the journal
``<name>.episodes.jsonl`` gets one JSON line per finished episode (policy, seed, the
contents hash of the policy's file and its metrics), each appended in one write and
fsynced. A kill can only tear the line being written; reading keeps the complete lines
and drops the torn tail. ``resume=true`` replays the journal's episodes instead of
running them again, if it was written by the same evaluation setting (its first line
records the config; one written before the simulator's keys were renamed ``sim`` records
them as ``env`` and is read under today's names).

Episodes are matched by the *contents* of the files they depend on, never by path:
the setting holds each input file (``layout.path``, ``tasks.path``) as its sha256
(:func:`with_file_digests`), so a map replaced at the same path refuses the resume and
names the key; each learned policy's episodes carry its checkpoint's sha256, so a
checkpoint replaced at the same path runs its own episodes again (the others are
kept). A journal of the first format, which matched paths, is refused.
"""

from __future__ import annotations

import hashlib
import json
import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from rtaw_marl.errors import ConfigError
from rtaw_marl.sim.lorr import read_problem
from rtaw_marl.sim.maps import resolve_path
from rtaw_marl.utils.atomic import disk_full_guard
from rtaw_marl.utils.renamed import upgrade_config
from rtaw_marl.utils.signals import signals_held

__all__ = [
    "FORMAT",
    "NOT_SETTING",
    "EpisodeJournal",
    "file_digest",
    "journal_path",
    "with_file_digests",
]

#: ``rtaw-eval`` options that do not change an episode's outcome: a resumed evaluation
#: may differ in them (policies and seeds are matched episode by episode), and
#: ``rtaw-results`` does not tell settings apart by them.
NOT_SETTING = (
    "policy", "checkpoint", "pretrained", "seeds", "compare_to", "lower_bound", "output",
    "resume", "progress", "torch_threads",
)  # fmt: skip

FORMAT = "rtaw_marl.episodes/2"
#: The first format: episodes keyed by file paths (a replaced file was replayed).
_PATH_KEYED = "rtaw_marl.episodes/1"
_DIGEST = "sha256:"


def journal_path(output: str | Path) -> Path:
    """``runs/x/results.json`` -> ``runs/x/results.episodes.jsonl``."""
    output = Path(output)
    return output.with_name(f"{output.stem}.episodes.jsonl")


def file_digest(path: str | Path) -> str:
    """``sha256:<hex>`` of a file's contents (read in chunks: checkpoints and maps are
    megabytes, read once per run)."""
    digest = hashlib.sha256()
    with open(path, "rb") as fh:
        for chunk in iter(lambda: fh.read(1 << 20), b""):
            digest.update(chunk)
    return _DIGEST + digest.hexdigest()


def with_file_digests(setting: Mapping[str, Any]) -> dict[str, Any]:
    """``setting`` with every file it names (a ``path`` key at any depth: the layout's,
    the task stream's; a LoRR ``problem``: its four files) replaced by the file's
    :func:`file_digest`, so that two settings
    match when their files have the same contents, wherever they lie."""
    out: dict[str, Any] = {}
    for key, value in setting.items():
        if isinstance(value, Mapping):
            out[key] = with_file_digests(value)
        elif key == "path" and isinstance(value, str):
            # The file a reader loads (``builtin:NAME`` is a shipped map), not the string.
            out[key] = file_digest(resolve_path(value))
        elif key == "problem" and isinstance(value, str):
            # A LoRR problem: the JSON and the map, agent and task files it names.
            problem = read_problem(value)
            files = (problem.path, problem.map_path, problem.agents_path, problem.tasks_path)
            out[key] = [file_digest(f) for f in files]
        else:
            out[key] = value
    return out


class EpisodeJournal:
    """The finished episodes of one evaluation setting.

    Args:
        path: The journal file.
        setting: What makes two evaluations' episodes interchangeable (the config
            without the policy list, seeds and output options; input files as their
            digests, :func:`with_file_digests`); stored in the header.
        resume: Keep the episodes of an existing journal with the same setting;
            otherwise an existing journal is replaced.
        sources: Policy name -> :func:`file_digest` of the file it was loaded from (a
            checkpoint, a shipped policy); rules have none. A journalled episode of a
            policy whose file has changed is not replayed (see :attr:`stale`).

    Raises:
        ConfigError: ``resume`` is set and the journal holds another setting, is of the
            path-keyed first format, or is not a journal.
        DiskFullError: The disk filled while writing; the journal keeps what it holds.
    """

    def __init__(
        self,
        path: str | Path,
        setting: Mapping[str, Any],
        resume: bool,
        sources: Mapping[str, str] | None = None,
    ) -> None:
        self.path = Path(path)
        self.setting = json.loads(json.dumps(setting))
        self.sources = dict(sources or {})
        self.episodes: dict[tuple[str, int], dict[str, float]] = {}
        #: Policy -> ``(journalled episodes not replayed, their digest)``: its file changed.
        self.stale: dict[str, tuple[int, str | None]] = {}
        self._file = None
        if resume and self.path.exists():
            self._replay()
            mode = "ab"
        else:
            mode = "wb"
        self._file = open(self.path, mode)  # noqa: SIM115 (closed by close())
        if mode == "wb":
            self._append({"format": FORMAT, "setting": self.setting})

    def get(self, policy: str, seed: int) -> dict[str, float] | None:
        """The metrics of a finished episode, or ``None``."""
        return self.episodes.get((policy, seed))

    def record(self, policy: str, seed: int, metrics: Mapping[str, float]) -> None:
        """Append one finished episode (durable when this returns)."""
        entry = {"policy": policy, "source": self.sources.get(policy), "seed": seed}
        # Written and counted together: a signal in between would make the interrupt's
        # message count a line that is not on disk (or miss one that is).
        with signals_held():
            self._append({**entry, "metrics": dict(metrics)}, self._kept())
            self.episodes[(policy, seed)] = dict(metrics)

    def close(self) -> None:
        """Close the file (every line is already on disk); closing twice is harmless."""
        if self._file is not None and not self._file.closed:
            with disk_full_guard(self.path, self._kept()):
                self._file.close()

    def _kept(self) -> str:
        return f"the journal keeps {self.held()}: run the same command with resume=true to continue"

    def held(self) -> str:
        """``3 finished episodes``: what the journal holds, for a message."""
        n = len(self.episodes)
        return f"{n} finished episode{'' if n == 1 else 's'}"

    def _append(self, entry: Mapping[str, Any], kept: str | None = None) -> None:
        with disk_full_guard(self.path, kept or self._kept()):
            self._file.write((json.dumps(entry) + "\n").encode())
            self._file.flush()
            os.fsync(self._file.fileno())

    def _replay(self) -> None:
        data = self.path.read_bytes()
        complete = data[: data.rfind(b"\n") + 1]
        if len(complete) < len(data):
            # A kill tore the last line: drop it so the next append starts a fresh line.
            with open(self.path, "r+b") as fh:
                fh.truncate(len(complete))
        lines = complete.decode(errors="replace").splitlines()
        self._check_header(lines[0] if lines else "")
        for line in lines[1:]:
            entry = json.loads(line)
            policy, source = entry["policy"], entry.get("source")
            if source != self.sources.get(policy):
                count, _ = self.stale.get(policy, (0, None))
                self.stale[policy] = (count + 1, source)
                continue
            self.episodes[(policy, int(entry["seed"]))] = entry["metrics"]

    def _check_header(self, line: str) -> None:
        try:
            header = json.loads(line) if line else {}
        except json.JSONDecodeError:
            header = {}
        fmt = header.get("format") if isinstance(header, dict) else None
        if fmt == _PATH_KEYED:
            raise ConfigError(
                f"resume=true: {self.path} is an older journal ({fmt}) that matched episodes "
                "by file paths, not contents, so its episodes cannot be trusted; drop "
                "resume=true to run them again"
            )
        if fmt != FORMAT:
            raise ConfigError(f"resume=true: {self.path} is not an episode journal")
        setting = header["setting"]
        if isinstance(setting, dict):  # written before the simulator's keys were "sim": "env"
            setting = upgrade_config(setting)
        if setting != self.setting:
            raise ConfigError(
                f"resume=true: {self.path} holds episodes of another setting "
                f"(differs in {', '.join(_differences(setting, self.setting))}); "
                "use another output or drop resume"
            )


def _differences(old: Mapping[str, Any], new: Mapping[str, Any], prefix: str = "") -> list[str]:
    keys = sorted(set(old) | set(new))
    out: list[str] = []
    for key in keys:
        a, b = old.get(key), new.get(key)
        if isinstance(a, Mapping) and isinstance(b, Mapping):
            out += _differences(a, b, f"{prefix}{key}.")
        elif a != b:
            out.append(f"{prefix}{key}: {_shown(a)} -> {_shown(b)}")
    return out


def _shown(value: Any) -> str:
    """A value for a difference line; a digest as its first 12 hex digits."""
    if isinstance(value, str) and value.startswith(_DIGEST):
        return f"contents sha256 {value[len(_DIGEST) : len(_DIGEST) + 12]}"
    return repr(value)
