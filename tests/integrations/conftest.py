"""One torch thread per test: the networks here are tiny, and on a 2-core machine running
two test workers, extra threads only contend (512 MaskablePPO steps: 18 s with torch's
default threads under load, 1 s with one)."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

try:
    import torch
except ImportError:  # the env-only install: the tests that need torch skip
    torch = None


@pytest.fixture(autouse=True)
def _one_torch_thread() -> Iterator[None]:
    if torch is None:
        yield
        return
    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    try:
        yield
    finally:
        torch.set_num_threads(threads)
