"""Outlines measured without a model in the pybullet cell: a fracture's 6 pieces scattered, one frame, every vertex.

The pieces are the cell's bodies, all of one colour, turned at random; the camera's frame alone gives
their top faces' vertices, checked against the simulator's pose of each body (evaluation only).

TinyRenderer samples pixel centres, so a side's edge is a staircase: the lines it allows are
measured (``outline_unknown_edges.aliased_line``), but a side whose slope in the image is a simple
fraction ``p / q`` (a row or column, a diagonal, 1 in 2) repeats its pattern every ``q`` pixels and
is known to about ``1 / (2 q)`` px only, however long. So most vertices are within a tenth of a
millimetre, and every one within a quarter (benchmarks/unknown_outlines.py has the distribution).
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


@pytest.mark.parametrize("seed", [1, 2])
def test_every_vertex_of_six_scattered_pieces_is_measured_by_truth(seed: int) -> None:
    pieces = fracture((0.20, 0.15, 0.02), 6, 0.002, seed)
    rng = np.random.default_rng(seed)
    with WorkCell() as cell:
        for piece, (x, y) in zip(pieces, PLACES, strict=True):
            x, y, yaw = x + rng.uniform(-0.01, 0.01), y + rng.uniform(-0.02, 0.02), rng.uniform(-math.pi, math.pi)
            kind = ObjectType(f"piece {piece.index}", shape=piece.prism)
            cell.add_object(kind, "red", x, y, yaw, name=str(piece.index))
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
        assert len(set(np.argmin(distances, axis=1).tolist())) == len(true)  # each vertex its own
        errors.append(1000 * distances.min(axis=1))
        x, y = outline.outline_m.T
        assert np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y) > 0  # counter-clockwise
    every = np.concatenate(errors)
    shown = [np.round(e, 3).tolist() for e in errors]
    assert np.all(every < 0.25), shown
    assert np.mean(every < 0.1) >= 0.9 and float(every.mean()) < 0.04, shown
