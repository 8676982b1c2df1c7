"""Parts that touch where they start, in the pybullet cell: each ends within,, none left unpicked.

Two identical red cubes side by side (one blob no face explains), two identical ells (one blob)
and a three-piece fresco with two pieces touching: the look before each pick fails on the blob
(or on the neighbour beside the part), ``Separate`` pushes a part aside, and every part is then
picked, placed and corrected as usual. The scenes are ``tests/touching_scenes.py``'s; the rest of
them are run by ``benchmarks/touching.py`` (docs/perception.md has the figures).
"""

from __future__ import annotations

from pathlib import Path

import pytest
from touching_scenes import scene

from bt_arrange.behaviours import Separate
from bt_arrange_sim.pybullet.runs import SimulatedRun


@pytest.mark.parametrize("name", ["two red cubes", "two identical ells", "fresco of 3, two touching"])
def test_parts_that_start_touching_are_separated_and_each_ends_within(name: str, tmp_path: Path) -> None:
    root, starts = scene(name, tmp_path)
    with SimulatedRun(root, starts) as run:
        report = run.run()
    for outcome in report.objects:
        assert outcome.status == "within", outcome
        assert outcome.final_offset_truth_mm is not None and outcome.final_offset_truth_mm < 1.0, outcome
    # The report says what happened: a part of the touching pair was pushed aside before a pick.
    assert sum(outcome.separations for outcome in report.objects) >= 1, "the scene's parts did not touch?"
    separated = [node for node in root.iterate() if isinstance(node, Separate) and node.pushed_mm is not None]
    assert "touching parts of one colour, separated" in separated[0].feedback_message
