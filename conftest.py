"""Test tiers for both suites (tests/ and benchmarks/tests/).

Every test has exactly one tier, its closest marker among ``unit``, ``integration`` and
``system`` (a test's own marker before its class's and its module's ``pytestmark``):

* ``unit``: fast, in-process, no training beyond a few steps; ``make test-fast``;
* ``integration``: several parts together (CLI runs, short training, other libraries);
* ``system``: the outside world: venv installs, LoRR's compiled kit, the browser, Ray.

``pytest --tier unit`` runs the tests whose tier is ``unit`` (``-m unit`` would also
take an integration test inside a unit module). A test without a tier fails collection.
"""

from __future__ import annotations

import pytest

TIERS = ("unit", "integration", "system")


def pytest_addoption(parser: pytest.Parser) -> None:
    parser.addoption(
        "--tier",
        action="append",
        choices=TIERS,
        help="run only the tests of this tier (repeatable); default: every tier",
    )


def pytest_configure(config: pytest.Config) -> None:
    for tier in TIERS:
        config.addinivalue_line("markers", f"{tier}: the {tier} tier (see conftest.py)")


def tier_of(item: pytest.Item) -> str | None:
    """The closest tier marker of ``item`` (function, then class, then module)."""
    return next((m.name for m in item.iter_markers() if m.name in TIERS), None)


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    untiered = [item.nodeid for item in items if tier_of(item) is None]
    if untiered:
        raise pytest.UsageError(
            f"{len(untiered)} tests have no tier (mark the module with pytestmark = "
            f"pytest.mark.unit, .integration or .system): {', '.join(untiered[:5])}"
        )
    wanted = config.getoption("--tier")
    if not wanted:
        return
    keep = [item for item in items if tier_of(item) in wanted]
    dropped = [item for item in items if tier_of(item) not in wanted]
    config.hook.pytest_deselected(items=dropped)
    items[:] = keep
