"""Two fresco pieces of one colour half a millimetre apart in the pybullet cell, seen by its top camera.

The morphology closes their gap, but the image shows it (TinyRenderer's pixels are point
samples): the mask is cut along it and each piece is a face of its own, found before picking
(no expected place, as Detect looks) and at its target (as Inspect does), against the
simulator's truth (evaluation only). The registration on free edges, where a blur hides the
gap, is tested on synthetic frames (tests/test_perception_merged.py).
"""

from __future__ import annotations

import math

import pytest
from merged_pieces import moved_towards, neighbours

from bt_arrange.objects import ObjectType
from bt_arrange.perception import PartDetector, WorldRegion
from bt_arrange_sim.pybullet.cell import WorkCell


@pytest.mark.parametrize(("seed", "gap_mm"), [(0, 0.5), (2, 0.6)])
def test_two_merged_pieces_are_each_measured_at_their_targets_within_a_tenth_by_truth(seed, gap_mm) -> None:
    a, b = neighbours(seed)
    ax, ay = moved_towards(a, b, gap_mm / 1000)
    with WorkCell() as cell:
        kinds = {"a": ObjectType(f"tile {a.index}", shape=a.prism), "b": ObjectType(f"tile {b.index}", shape=b.prism)}
        cell.add_object(kinds["a"], "red", ax, ay, a.yaw_rad, name="a")
        cell.add_object(kinds["b"], "red", b.x_m, b.y_m, b.yaw_rad, name="b")
        cell.settle(0.3)
        frame = cell.robot.camera.capture()
        for name, piece in (("a", a), ("b", b)):
            detector = PartDetector().for_object(kinds[name])
            x, y, yaw = cell.part_planar_truth(name)
            for roi in (None, WorldRegion.around(piece.x_m, piece.y_m, 0.05)):
                detection = detector.detect(frame, "red", roi=roi)
                assert detection.found, detection.reason
                pose = detection.pose_world
                assert 1000 * math.hypot(pose.x_m - x, pose.y_m - y) < 0.1
                assert abs(math.degrees(math.remainder(pose.yaw_rad - yaw, 2 * math.pi))) < 0.1
