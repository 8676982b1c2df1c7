"""Fixtures every test shares: a clean py_trees blackboard around each test, and a test clock.

The fake devices live in ``tests/fakes.py``; tests import them with ``from fakes import ...``
(pytest puts this folder on ``sys.path``, as ``tests/`` has no ``__init__.py``).
"""

from __future__ import annotations

from collections.abc import Iterator

import py_trees
import pytest
from fakes import FakeClock, make_context

from bt_arrange.behaviours import Context


@pytest.fixture(autouse=True)
def clean_blackboard() -> Iterator[None]:
    """No keys, clients or activity stream left over from another test, before or after."""
    py_trees.blackboard.Blackboard.clear()
    py_trees.blackboard.Blackboard.disable_activity_stream()
    yield
    py_trees.blackboard.Blackboard.clear()


@pytest.fixture
def clock() -> FakeClock:
    """World time at 0 s, advanced only by the test (or ``tick_until_done``)."""
    return FakeClock()


@pytest.fixture
def context(clock: FakeClock) -> Context:
    """A context over fake devices (arm at home, gripper open, no cubes) on the test clock."""
    return make_context(clock)
