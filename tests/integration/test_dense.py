"""Dense arrangements in the cell: a 2 x 2 block with 2 mm gaps, and identical faces 2 mm apart on camera."""

from __future__ import annotations

import pytest

from bt_arrange.objects import CUBE
from bt_arrange.perception import PartDetector
from bt_arrange.perception.detection import WorldRegion
from bt_arrange.plan.layout import Rect, gap_m
from bt_arrange.trees import Target, arrangement
from bt_arrange_sim.config import CellConfig
from bt_arrange_sim.pybullet.cell import WorkCell
from bt_arrange_sim.pybullet.runs import SimulatedRun
from bt_arrange_sim.scenes import scatter

CUBE_EDGE_M = CUBE.size_m[0]
PITCH_M = CUBE_EDGE_M + 0.002


def test_identical_faces_2_mm_apart_are_separate_cubes_on_camera() -> None:
    detector = PartDetector()
    with WorkCell(CellConfig()) as cell:
        for i in range(3):
            cell.add_cube("green", 0.45 + i * PITCH_M, 0.05, 0.0, name=f"g{i}")
        cell.settle(0.3)
        frame = cell.camera.capture()
        # The search at a quarter of the resolution merges them; looked at again at full resolution, three.
        assert len(detector.locate(frame, "green")) == 3
        for i in range(3):
            x, y, _ = cell.part_planar_truth(f"g{i}")
            detection = detector.detect(frame, "green", roi=WorldRegion.around(x, y, 0.02))
            assert detection.found, detection.reason
            planar = detection.planar
            assert planar is not None
            assert abs(planar.x_m - x) < 0.0002 and abs(planar.y_m - y) < 0.0002


def test_a_2x2_block_with_2_mm_gaps_ends_within_1_mm_without_touching_or_shoving_a_neighbour() -> None:
    targets = [
        Target("red", 0.45, 0.0),
        Target("green", 0.45 + PITCH_M, 0.0),
        Target("blue", 0.45, PITCH_M),
        Target("yellow", 0.45 + PITCH_M, PITCH_M),
    ]
    root = arrangement(targets)
    with SimulatedRun(root, scatter([t.colour for t in targets], 1, avoid=targets)) as run:
        report = run.run()
        feedback = {t.behaviour: t.feedback for t in report.transitions if t.new == "SUCCESS"}
        truth = {t.obj: run.cell.part_planar_truth(t.obj) for t in targets}
    assert report.tree_status == "SUCCESS"
    for outcome in report.objects:
        assert outcome.final_offset_truth_mm < 1.0, outcome
    # The last one, boxed in on two sides, was released away from them and pushed home.
    assert feedback["place yellow"].startswith("yellow released +0, +14 mm from its target")
    # Each earlier cube was looked at again after its neighbours and barely moved (ground truth).
    moved = {o.name: o.moved_by_later_truth_mm for o in report.objects}
    assert moved["yellow"] is None and all(moved[n] is not None and moved[n] < 0.3 for n in ("red", "green", "blue"))
    rects = [Rect(x, y, yaw, CUBE_EDGE_M / 2, CUBE_EDGE_M / 2) for x, y, yaw in truth.values()]
    gaps = [gap_m(a, b) for i, a in enumerate(rects) for b in rects[i + 1 :]]
    assert min(gaps) > 0.0005, "no two cubes touch"


@pytest.mark.parametrize("gap_mm", [1.0])
def test_a_plan_too_tight_to_build_is_refused_before_the_cell_is_built(gap_mm: float) -> None:
    from bt_arrange.errors import PlanError

    with pytest.raises(PlanError, match=r"^targets red and green are 1.0 mm apart"):
        arrangement([Target("red", 0.45, 0.0), Target("green", 0.45 + CUBE_EDGE_M + gap_mm / 1000, 0.0)])
