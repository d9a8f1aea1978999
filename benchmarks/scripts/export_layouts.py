"""Write the paper's layouts A-E as ASCII files and a figure, for the docs.

Usage: ``python -m benchmarks.scripts.export_layouts`` -> ``docs/layouts/<P>.txt`` ('.' free,
'@' shelf, the format ``layout.path=FILE`` loads) and ``docs/img/layouts.png``.
"""

from __future__ import annotations

import sys
from pathlib import Path

import matplotlib

from rtaw_marl.sim.options import PresetLayoutConfig

matplotlib.use("Agg")
import matplotlib.pyplot as plt

from rtaw_marl.sim.warehouse_layouts import PRESETS

DOCS = Path(__file__).resolve().parents[2] / "docs"


def main() -> int:
    (DOCS / "layouts").mkdir(parents=True, exist_ok=True)
    (DOCS / "img").mkdir(parents=True, exist_ok=True)
    fig, axes = plt.subplots(1, len(PRESETS), figsize=(3 * len(PRESETS), 3.2), dpi=100)
    for ax, preset in zip(axes, PRESETS, strict=True):
        layout = PresetLayoutConfig(preset=preset).build()
        (DOCS / "layouts" / f"{preset}.txt").write_text(layout.to_ascii() + "\n")
        image = (~layout.obstacles).astype(float)
        image[layout.pickup] = 0.75
        image[layout.delivery] = 0.45
        ax.imshow(image, cmap="gray", vmin=0, vmax=1, interpolation="nearest")
        ax.set_title(f"{preset}: compactness {layout.compactness:.2f}", fontsize=9)
        ax.set_axis_off()
    fig.suptitle("Layouts A-E, 60x60 (black: shelves; grey: pickup / delivery stations)")
    fig.tight_layout()
    fig.savefig(DOCS / "img" / "layouts.png")
    print(f"wrote {DOCS / 'layouts'} and {DOCS / 'img' / 'layouts.png'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
