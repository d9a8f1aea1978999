"""Short labels for learned policies in tables, journals and result files.

A shipped policy is labelled by its name (``generalist_plus``); a checkpoint file by the
end of its path (``runs/demo/checkpoints/best.pt`` -> ``demo/best``), never by the whole
path, which made tables unreadable and results.json keys machine-specific.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

__all__ = ["OLD_PREFIX", "checkpoint_labels", "upgrade_label"]

#: What learned policies' labels began with before they were short
#: (``rtaw:generalist_plus@k32``); files written then still say it.
OLD_PREFIX = "rtaw:"


def upgrade_label(label: str) -> str:
    """A label read from an older file as the commands write it now
    (``rtaw:generalist_plus@k32`` -> ``generalist_plus@k32``); others unchanged."""
    return label.removeprefix(OLD_PREFIX)


def checkpoint_labels(sources: Sequence[str]) -> list[str]:
    """Short distinct labels for checkpoint paths: the file's stem after its run folder
    (``runs/demo/checkpoints/best.pt`` -> ``demo/best``), with more of the path where two
    would be equal; a shipped name (no path) is its own label."""
    parts = [[p for p in Path(s).with_suffix("").parts if p != "checkpoints"] for s in sources]
    depth = [min(2, len(p)) for p in parts]
    while True:
        labels = ["/".join(p[-d:]) for p, d in zip(parts, depth, strict=True)]
        clashing = {i for i, label in enumerate(labels) if labels.count(label) > 1}
        grow = [i for i in clashing if depth[i] < len(parts[i])]
        if not grow:
            return labels if not clashing else [str(s) for s in sources]
        for i in grow:
            depth[i] += 1
