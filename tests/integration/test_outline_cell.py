"""Perception of outlines on frames rendered by the pybullet cell, checked against its ground truth."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bt_arrange.geometry import fold_yaw
from bt_arrange.objects import ObjectType
from bt_arrange.perception import DetectionStatus, PartDetector
from bt_arrange.shapes import Prism
from bt_arrange_sim.pybullet.cell import WorkCell


def part(name: str, points_mm: list[list[float]]) -> ObjectType:
    return ObjectType(name, shape=Prism.from_outline(np.asarray(points_mm, dtype=float) / 1000, 0.02))


FRAGMENT = part("fragment", [[0, 0], [45, 4], [60, 30], [35, 28], [30, 50], [5, 40]])
ELL = part("ell", [[0, 0], [60, 0], [60, 20], [20, 20], [20, 50], [0, 50]])
TRIANGLE = part("triangle", [[0, 0], [60, 0], [15, 45]])
PENTAGON = part(
    "pentagon", [[30 * math.cos(2 * math.pi * k / 5), 30 * math.sin(2 * math.pi * k / 5)] for k in range(5)]
)
PLACES = [("red", 0.36, 0.25), ("green", 0.62, 0.22), ("blue", 0.40, -0.22), ("yellow", 0.60, -0.26)]


def test_non_convex_and_symmetric_outlines_are_found_at_many_yaws_in_the_cells_frames() -> None:
    kinds = [FRAGMENT, ELL, TRIANGLE, PENTAGON]
    with WorkCell() as cell:
        for turn in range(3):
            for k, ((colour, x, y), kind) in enumerate(zip(PLACES, kinds, strict=True)):
                yaw = -math.pi + 2 * math.pi * (turn + 0.3 * k + 0.1) / 3
                cell.add_object(kind, colour, x, y, yaw, name=kind.name)
            cell.settle(0.05)
            frame = cell.camera.capture()
            for (colour, *_), kind in zip(PLACES, kinds, strict=True):
                detection = PartDetector().for_object(kind).detect(frame, colour)
                assert detection.found, detection.reason
                true_x, true_y, true_yaw = cell.part_planar_truth(kind.name)
                pose = detection.pose_world
                assert 1000 * math.hypot(pose.x_m - true_x, pose.y_m - true_y) < 0.1
                assert abs(math.degrees(fold_yaw(pose.yaw_rad - true_yaw, kind.shape.symmetry_rad))) < 0.15
            for kind in kinds:
                cell.remove_part(kind.name)


def test_two_parts_of_one_colour_are_told_apart_by_outline_in_the_cells_frames() -> None:
    with WorkCell() as cell:
        cell.add_object(FRAGMENT, "red", 0.42, 0.12, 2.2, name="fragment")
        cell.add_object(ELL, "red", 0.58, -0.12, -0.9, name="ell")
        cell.settle(0.05)
        frame = cell.camera.capture()
        for kind in (FRAGMENT, ELL):
            detection = PartDetector().for_object(kind).detect(frame, "red")
            assert detection.found, detection.reason
            true_x, true_y, _ = cell.part_planar_truth(kind.name)
            assert (detection.pose_world.x_m, detection.pose_world.y_m) == pytest.approx((true_x, true_y), abs=1e-4)
        cell.remove_part("ell")
        cell.settle(0.01)
        alone = PartDetector().for_object(ELL).detect(cell.camera.capture(), "red")
        assert alone.status is DetectionStatus.WRONG_OUTLINE, alone.reason
