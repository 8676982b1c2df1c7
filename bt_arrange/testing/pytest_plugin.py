"""The pytest plugin that installing bt-arrange registers (entry point ``pytest11``, name ``bt_arrange``).

- the ``bt_blackboard`` fixture: py_trees' blackboard is process-wide, so keys, clients and the
  activity stream of one test would leak into the next; the fixture clears them before and after
  the test, and gives the ``Blackboard`` class (``bt_blackboard.set(key, value)``, ``.get(key)``,
  ``.exists(key)``);
- the dependencies' warnings that a user can do nothing about (placo importing hppfcl under its
  former name) are filtered out of the test output.

The module imports nothing heavy: pytest loads it in every run of a project that has bt-arrange
installed, whether its tests use bt-arrange or not.
"""

from __future__ import annotations

from collections.abc import Iterator

import py_trees
import pytest

#: Warnings of bt-arrange's dependencies that say nothing to a user, as ``filterwarnings`` lines.
DEPENDENCY_WARNINGS = ("ignore:Please update your 'hppfcl' imports:DeprecationWarning",)


def pytest_configure(config: pytest.Config) -> None:
    """Filter the dependencies' warnings, after the project's own ``filterwarnings`` (``error`` among them).

    The last matching line wins, so even a project that turns every warning into an error imports
    bt-arrange; ``-W`` options on the command line still come last.
    """
    for line in DEPENDENCY_WARNINGS:
        if line not in config.getini("filterwarnings"):
            config.addinivalue_line("filterwarnings", line)


def clear_blackboard() -> None:
    """Forget every key, value and client of py_trees' blackboard, and stop its activity stream."""
    py_trees.blackboard.Blackboard.clear()
    py_trees.blackboard.Blackboard.disable_activity_stream()


@pytest.fixture
def bt_blackboard() -> Iterator[type[py_trees.blackboard.Blackboard]]:
    """py_trees' blackboard, empty when the test starts and emptied again when it ends."""
    clear_blackboard()
    yield py_trees.blackboard.Blackboard
    clear_blackboard()
