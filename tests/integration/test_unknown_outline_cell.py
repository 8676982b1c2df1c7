"""Outlines measured without a model in the pybullet cell: a fracture's 6 pieces scattered, one frame, every vertex.

The pieces are the cell's bodies, all of one colour, turned at random; the camera's frame alone gives
their top faces' vertices, checked against the simulator's pose of each body (evaluation only).
TinyRenderer samples pixel centres: a side within a pixel of a row or column over its whole length
shows no step and is known to half a pixel, so the scatter's yaws keep every side at least 1.5
degrees off the image's rows and columns (docs: the benchmark, benchmarks/unknown_outlines.py, measures all yaws).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from bt_arrange.objects import ObjectType
from bt_arrange.perception import PartDetector, measure_unknown_outlines
from bt_arrange.shapes.base import footprint_m
from bt_arrange.shapes.fracture import fracture
from bt_arrange_sim.pybullet.cell import WorkCell

PLACES = [(0.38, -0.25), (0.38, 0.0), (0.38, 0.25), (0.62, -0.25), (0.62, 0.0), (0.62, 0.25)]
#: No side within this of an image axis (the camera looks straight down, image axes along world x and y).
AXIS_CLEARANCE_DEG = 1.5


def off_axis_yaw(rng: np.random.Generator, outline: np.ndarray, camera_yaw_deg: float) -> float:
    """A random yaw that keeps every side of ``outline`` at least ``AXIS_CLEARANCE_DEG`` off the image's axes."""
    sides = np.roll(outline, -1, axis=0) - outline
    angles = np.degrees(np.arctan2(sides[:, 1], sides[:, 0])) - camera_yaw_deg
    while True:
        yaw = float(rng.uniform(-math.pi, math.pi))
        off = (angles + math.degrees(yaw)) % 90.0
        if np.all(np.minimum(off, 90.0 - off) >= AXIS_CLEARANCE_DEG):
            return yaw


@pytest.mark.parametrize("seed", [1, 2])
def test_every_vertex_of_six_scattered_pieces_is_within_a_tenth_by_truth(seed: int) -> None:
    pieces = fracture((0.20, 0.15, 0.02), 6, 0.002, seed)
    rng = np.random.default_rng(seed)
    with WorkCell() as cell:
        rotation = cell.camera.pose_world.rotation  # the image's x axis (right) in the world
        camera_yaw_deg = math.degrees(math.atan2(rotation[1, 0], rotation[0, 0]))
        for piece, (x, y) in zip(pieces, PLACES, strict=True):
            x, y = x + rng.uniform(-0.01, 0.01), y + rng.uniform(-0.02, 0.02)
            yaw = off_axis_yaw(rng, piece.prism.outline_m, camera_yaw_deg)
            cell.add_object(
                ObjectType(f"piece {piece.index}", shape=piece.prism), "red", x, y, yaw, name=str(piece.index)
            )
        cell.settle(0.3)
        frame = cell.camera.capture()
        truth = []
        for piece in pieces:
            pose = cell.part_pose_truth(str(piece.index))
            truth.append(footprint_m(piece.prism, pose.x_m, pose.y_m, pose.yaw_rad))
    outlines, problems = measure_unknown_outlines(PartDetector(), frame, "red", 0.02)
    assert problems == []
    assert len(outlines) == len(pieces)
    errors = []
    for outline in outlines:
        true = min(truth, key=lambda t: float(np.hypot(*(t.mean(axis=0) - outline.centroid_m))))
        assert len(outline.outline_m) == len(true)
        distances = np.hypot(*(outline.outline_m[:, None, :] - true[None, :, :]).transpose(2, 0, 1))
        errors.append(1000 * distances.min(axis=1))
        x, y = outline.outline_m.T
        assert np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y) > 0  # counter-clockwise
    every = np.concatenate(errors)
    assert np.all(every < 0.1), [np.round(e, 3) for e in errors]
