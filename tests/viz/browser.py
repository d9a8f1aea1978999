"""Headless Chromium for the viewer's tests and benchmark (Debian's chromium and its
chromedriver, driven by Selenium; ``make browser`` installs them)."""

from __future__ import annotations

import os
import shutil
import tempfile
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import pytest

CHROMIUM = "/usr/bin/chromium"
CHROMEDRIVER = "/usr/bin/chromedriver"

# Without the background-networking flags Chromium keeps trying to reach Google on a
# machine with no network.
FLAGS = (
    "--headless=new",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--disable-dev-shm-usage",
    "--hide-scrollbars",
    "--force-device-scale-factor=1",
)


def browser_or_skip() -> None:
    """Fail (or skip, with ``RTAW_NO_BROWSER=1``) when Chromium is not installed."""
    missing = [p for p in (CHROMIUM, CHROMEDRIVER) if not Path(p).exists()]
    if not missing:
        return
    why = f"{', '.join(missing)} missing: `make browser` installs chromium and chromium-driver"
    if os.environ.get("RTAW_NO_BROWSER") == "1":
        pytest.skip(why)
    pytest.fail(why)


@contextmanager
def chromium(width: int = 1200, height: int = 800) -> Iterator[Any]:
    """A Selenium driver of headless Chromium with a ``width x height`` viewport."""
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    profile = tempfile.mkdtemp(prefix="rtaw-chromium-")
    options = webdriver.ChromeOptions()
    options.binary_location = CHROMIUM
    for flag in FLAGS:
        options.add_argument(flag)
    options.add_argument(f"--user-data-dir={profile}")
    options.add_argument(f"--window-size={width},{height}")
    options.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    driver = webdriver.Chrome(service=Service(CHROMEDRIVER), options=options)
    try:
        yield driver
    finally:
        driver.quit()
        shutil.rmtree(profile, ignore_errors=True)


def open_view(driver: Any, path: Path, timeout: float = 60.0) -> None:
    """Load a viewer page and wait until its data is decoded."""
    driver.get(path.resolve().as_uri())
    deadline = time.monotonic() + timeout
    while not driver.execute_script("return Boolean(window.rtawView && window.rtawView.ready)"):
        errors = driver.execute_script("return window.rtawErrors || []")
        if errors:
            raise AssertionError(f"the page failed to load: {errors}")
        if time.monotonic() > deadline:
            raise AssertionError(f"the page did not load in {timeout} s")
        time.sleep(0.05)


def severe_logs(driver: Any) -> list[str]:
    """The console's errors since the last call."""
    return [e["message"] for e in driver.get_log("browser") if e["level"] == "SEVERE"]
