"""Fixtures every test shares: a clean py_trees blackboard around each test, and a test clock.

The fake devices are the testing kit's (``bt_arrange.testing``), and the clean blackboard is its
pytest plugin's ``bt_blackboard`` fixture. Installing bt-arrange registers that plugin by entry
point; a checkout whose install predates the entry point registers it here, once.
"""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from bt_arrange.behaviours import Context
from bt_arrange.testing import FakeClock, make_context, pytest_plugin


def pytest_configure(config: pytest.Config) -> None:
    """Register the kit's plugin unless its entry point did (registering it twice is an error)."""
    manager = config.pluginmanager
    if not manager.is_registered(pytest_plugin) and not manager.has_plugin("bt_arrange"):
        manager.register(pytest_plugin, "bt_arrange")


@pytest.fixture(autouse=True)
def clean_blackboard(bt_blackboard: object) -> Iterator[None]:
    """No keys, clients or activity stream left over from another test, before or after."""
    yield


@pytest.fixture
def clock() -> FakeClock:
    """World time at 0 s, advanced only by the test (or ``tick_until_done``)."""
    return FakeClock()


@pytest.fixture
def context(clock: FakeClock) -> Context:
    """A context over fake devices (arm at home, gripper open, no parts) on the test clock."""
    return make_context(clock=clock)
