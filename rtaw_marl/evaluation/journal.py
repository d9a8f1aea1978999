"""Finished episodes on disk as they finish, so a killed evaluation loses none of them.

``rtaw-eval`` writes ``results.json`` once, at the end. Beside it, the journal
``<name>.episodes.jsonl`` gets one JSON line per finished episode (policy, seed and its
metrics), each appended in one write and fsynced. A kill can only tear the line being
written; reading keeps the complete lines and drops the torn tail. ``resume=true``
replays the journal's episodes instead of running them again, if it was written by the
same evaluation setting (its first line records the config).
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from rtaw_marl.errors import ConfigError

__all__ = ["FORMAT", "EpisodeJournal", "journal_path"]

FORMAT = "rtaw_marl.episodes/1"


def journal_path(output: str | Path) -> Path:
    """``runs/x/results.json`` -> ``runs/x/results.episodes.jsonl``."""
    output = Path(output)
    return output.with_name(f"{output.stem}.episodes.jsonl")


class EpisodeJournal:
    """The finished episodes of one evaluation setting.

    Args:
        path: The journal file.
        setting: What makes two evaluations' episodes interchangeable (the config
            without the policy list, seeds and output options); stored in the header.
        resume: Keep the episodes of an existing journal with the same setting;
            otherwise an existing journal is replaced.

    Raises:
        ConfigError: ``resume`` is set and the journal holds another setting, or is not
            a journal.
    """

    def __init__(self, path: str | Path, setting: Mapping[str, Any], resume: bool) -> None:
        self.path = Path(path)
        self.setting = json.loads(json.dumps(setting))
        self.episodes: dict[tuple[str, int], dict[str, float]] = {}
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
        self.episodes[(policy, seed)] = dict(metrics)
        self._append({"policy": policy, "seed": seed, "metrics": dict(metrics)})

    def close(self) -> None:
        """Close the file (every line is already on disk)."""
        self._file.close()

    def _append(self, entry: Mapping[str, Any]) -> None:
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
        try:
            header = json.loads(lines[0]) if lines else {}
        except json.JSONDecodeError:
            header = {}
        if header.get("format") != FORMAT:
            raise ConfigError(f"resume=true: {self.path} is not an episode journal")
        if header["setting"] != self.setting:
            raise ConfigError(
                f"resume=true: {self.path} holds episodes of another setting "
                f"(differs in {', '.join(_differences(header['setting'], self.setting))}); "
                "use another output or drop resume"
            )
        for line in lines[1:]:
            entry = json.loads(line)
            self.episodes[(entry["policy"], int(entry["seed"]))] = entry["metrics"]


def _differences(old: Mapping[str, Any], new: Mapping[str, Any], prefix: str = "") -> list[str]:
    keys = sorted(set(old) | set(new))
    out: list[str] = []
    for key in keys:
        a, b = old.get(key), new.get(key)
        if isinstance(a, Mapping) and isinstance(b, Mapping):
            out += _differences(a, b, f"{prefix}{key}.")
        elif a != b:
            out.append(f"{prefix}{key}: {a!r} -> {b!r}")
    return out
