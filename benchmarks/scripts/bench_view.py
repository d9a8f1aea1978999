"""Benchmark of rtaw-view's page in headless Chromium: load time and frames per second.

Opens a viewer page (made by ``rtaw-view``) in Debian's headless Chromium (``make
browser``), waits until its data is decoded, then plays it at ``--speed`` timesteps per
second and counts the frames drawn in each second, twice: with the whole map in view
(every robot drawn) and zoomed in (cells of 12 pixels, following a robot). Prints the
file size, the load time, and the median frames per second and milliseconds of drawing
per frame of each phase.

    python -m benchmarks.scripts.bench_view VIEW.html [--seconds 8] [--speed 20]
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))

from tests.viz.browser import browser_or_skip, chromium, open_view, severe_logs


def _phase(driver, seconds: int) -> tuple[float, float]:
    """Median frames per second and drawing ms per frame over ``seconds`` windows."""
    fps, draw = [], []
    last = driver.execute_script("return window.rtawView.stats()")
    for _ in range(seconds):
        time.sleep(1.0)
        now = driver.execute_script("return window.rtawView.stats()")
        frames = now["frames"] - last["frames"]
        fps.append(frames)
        draw.append((now["drawMs"] - last["drawMs"]) / max(frames, 1))
        last = now
    return statistics.median(fps), statistics.median(draw)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("page", type=Path)
    parser.add_argument("--seconds", type=int, default=8)
    parser.add_argument("--speed", type=float, default=20.0)
    parser.add_argument("--width", type=int, default=1600)
    parser.add_argument("--height", type=int, default=900)
    args = parser.parse_args()
    browser_or_skip()
    print(f"page: {args.page} ({args.page.stat().st_size / 1e6:.1f} MB)")
    with chromium(args.width, args.height) as driver:
        start = time.perf_counter()
        open_view(driver, args.page, timeout=600)
        print(f"load (decode + keyframes): {time.perf_counter() - start:.1f} s")
        state = driver.execute_script("return window.rtawView.state()")
        print(f"robots {state['robots']}, timesteps {state['steps']}")
        driver.execute_script(f"window.rtawView.setSpeed({args.speed}); window.rtawView.play()")
        fps, ms = _phase(driver, args.seconds)
        print(
            f"whole map, playing at {args.speed:g} steps/s: {fps:.0f} frames/s, {ms:.1f} ms/frame"
        )
        driver.execute_script("window.rtawView.search('r0')")
        driver.execute_script(f"window.rtawView.setSpeed({args.speed}); window.rtawView.play()")
        fps, ms = _phase(driver, args.seconds)
        print(f"zoomed in, following robot 0: {fps:.0f} frames/s, {ms:.1f} ms/frame")
        driver.execute_script("window.rtawView.seek(0)")
        start = time.perf_counter()
        for t in range(0, state["steps"], max(1, state["steps"] // 20)):
            driver.execute_script(f"window.rtawView.seek({t})")
        seeks = len(range(0, state["steps"], max(1, state["steps"] // 20)))
        print(f"scrub: {(time.perf_counter() - start) / seeks * 1e3:.0f} ms per seek")
        errors = severe_logs(driver) + driver.execute_script("return window.rtawErrors")
        print(f"console errors: {len(errors)}")


if __name__ == "__main__":
    main()
