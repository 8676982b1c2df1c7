"""Parts that touch at the start: the perception and planning side, on synthetic frames.

The look before a pick must notice a neighbour of the part's colour that touches it, even where the
image shows the seam and the mask cuts the faces apart (``touching_pixels``); ``Separate`` sees
touching faces as one cluster (``touching_clusters``) and pushes the end part of the row across it
(``plan_separation``). The plan check lets parts start touching, and refuses parts that overlap.
The cell's runs are in ``integration/test_touching_cell.py``.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from bt_arrange.behaviours.separate import SEPARATION_MARGIN_M, plan_separation
from bt_arrange.objects import CUBE, ObjectStart, ObjectType
from bt_arrange.perception import DEFAULT_COLOUR_TABLE, DetectionStatus, PartDetector
from bt_arrange.perception.synthetic import SyntheticCube, SyntheticPrism, render_frame
from bt_arrange.perception.touching import MIN_TOUCHING_PX, touching_clusters, touching_pixels
from bt_arrange.plan.check import starts_overlap
from bt_arrange.settings import ManipulationSettings
from bt_arrange.shapes import Prism

EDGE_M = CUBE.shape.extent_m[0]
TOP_Z_M = 0.05  # the cube's top face above the table (the synthetic table is at z = 0)
RED = DEFAULT_COLOUR_TABLE["red"]


def red_cubes(*xy_m: tuple[float, float], yaw_rad: float = 0.0, blur_px: float = 0.0):
    return render_frame([SyntheticCube("red", x, y, yaw_rad) for x, y in xy_m], blur_sigma_px=blur_px)


@pytest.mark.parametrize("blur_px", [0.0, 1.0])
def test_two_touching_cubes_are_one_blob_that_no_face_explains(blur_px: float) -> None:
    frame = red_cubes((0.45, -0.15), (0.45 + EDGE_M + 0.0001, -0.15), blur_px=blur_px)
    detection = PartDetector().detect(frame, "red")
    assert detection.status is DetectionStatus.AMBIGUOUS, detection.reason
    assert "touching parts of one colour" in detection.reason


@pytest.mark.parametrize("gap_mm", [1.0, 2.0, 3.5])
def test_a_neighbour_whose_seam_the_image_shows_fills_the_ring_beside_the_part(gap_mm: float) -> None:
    # Closer (0.1 mm), the two faces are one blob: AMBIGUOUS, as the first test says.
    frame = red_cubes((0.45, -0.15), (0.45 + EDGE_M + gap_mm / 1000, -0.15))
    pixels = touching_pixels(frame, RED, CUBE.shape.outline_m, (0.45, -0.15, 0.0), TOP_Z_M, 7)
    assert pixels is not None and pixels >= MIN_TOUCHING_PX
    # A found pose a few pixels off (the lens' distortion, a calibration's error) finds the same face.
    shifted = touching_pixels(frame, RED, CUBE.shape.outline_m, (0.4515, -0.1485, 0.02), TOP_Z_M, 7)
    assert shifted == pixels


def test_a_part_alone_or_with_its_neighbour_a_centimetre_away_leaves_the_ring_empty() -> None:
    for neighbour_gap_m in (None, 0.010):
        xy = [(0.45, -0.15)] + ([] if neighbour_gap_m is None else [(0.45 + EDGE_M + neighbour_gap_m, -0.15)])
        frame = red_cubes(*xy)
        pixels = touching_pixels(frame, RED, CUBE.shape.outline_m, (0.45, -0.15, 0.0), TOP_Z_M, 7)
        assert pixels == 0


def test_a_neighbour_of_another_colour_is_not_counted() -> None:
    frame = render_frame([SyntheticCube("red", 0.45, -0.15), SyntheticCube("blue", 0.45 + EDGE_M + 0.0001, -0.15)])
    assert touching_pixels(frame, RED, CUBE.shape.outline_m, (0.45, -0.15, 0.0), TOP_Z_M, 7) == 0


def test_touching_faces_are_one_cluster_and_faces_apart_two() -> None:
    face_m2 = EDGE_M**2
    touching = touching_clusters(red_cubes((0.45, -0.15), (0.45 + EDGE_M + 0.0001, -0.15)), RED, TOP_Z_M, 7)
    assert len(touching) == 1 and touching[0].area_m2 / face_m2 == pytest.approx(2.0, rel=0.05)
    assert touching[0].holds(0.45, -0.15) and touching[0].holds(0.45 + EDGE_M, -0.15)
    apart = touching_clusters(red_cubes((0.45, -0.15), (0.45, 0.0)), RED, TOP_Z_M, 7)
    assert len(apart) == 2 and all(c.area_m2 / face_m2 == pytest.approx(1.0, rel=0.05) for c in apart)


def test_touching_fresco_like_outlines_of_one_colour_are_one_cluster() -> None:
    a = Prism(((-0.03, -0.02), (0.03, -0.02), (0.02, 0.02), (-0.03, 0.02)), 0.02)
    b = Prism(((-0.02, -0.02), (0.03, -0.02), (0.03, 0.02), (-0.03, 0.02)), 0.02)
    # Side by side along x: a's right edge (0.03 .. 0.02) against b's left edge (-0.02 .. -0.03), shifted to touch.
    frame = render_frame([SyntheticPrism("red", 0.45, -0.15, 0.0, a), SyntheticPrism("red", 0.5001, -0.15, 0.0, b)])
    clusters = touching_clusters(frame, RED, 0.02, 7)
    assert len(clusters) == 1


@pytest.mark.parametrize("yaw_deg", [0.0, 30.0, 90.0])
def test_the_push_aside_crosses_the_row_at_an_end_part_by_its_width_and_the_margin(yaw_deg: float) -> None:
    # Two 50 mm faces in a row along the yaw: a 100 x 50 mm rectangle.
    yaw = math.radians(yaw_deg)
    along, across = np.array([math.cos(yaw), math.sin(yaw)]), np.array([-math.sin(yaw), math.cos(yaw)])
    centre = np.array([0.5, -0.1])
    corners = [centre + sx * 0.05 * along + sy * 0.025 * across for sx, sy in ((1, 1), (-1, 1), (-1, -1), (1, -1))]
    contour = np.vstack(
        [np.linspace(p, q, 50, endpoint=False) for p, q in zip(corners, corners[1:] + corners[:1], strict=True)]
    )
    point, direction, distance_m, face_offset_m = plan_separation(contour, 0.008, np.array([0.5, 0.0]))
    assert abs(float(direction @ along)) < 1e-3  # across the row
    assert abs(abs(float((point - centre) @ along)) - 0.025) < 1e-3  # an end part's middle
    assert distance_m == pytest.approx(0.05 + SEPARATION_MARGIN_M, abs=1e-3)
    assert face_offset_m == pytest.approx(0.025, abs=1e-3)
    # Of both sides, the one that moves the part towards the point under the camera.
    assert float(direction @ (np.array([0.5, 0.0]) - centre)) >= -1e-9


def test_the_plan_check_lets_parts_start_touching_and_refuses_overlapping_ones() -> None:
    settings = ManipulationSettings()
    bar = ObjectType("bar", size_m=(0.08, 0.04, 0.04))
    first = ObjectStart("red", 0.45, -0.15, 0.0, "a", bar)
    assert not starts_overlap(first, ObjectStart("red", 0.45, -0.15 + 0.04, 0.0, "b", bar), settings)
    assert not starts_overlap(first, ObjectStart("red", 0.45 + 0.08, -0.15, 0.0, "b", bar), settings)
    assert starts_overlap(first, ObjectStart("red", 0.45 + 0.07, -0.15, 0.0, "b", bar), settings)
    assert starts_overlap(first, ObjectStart("red", 0.46, -0.14, 0.5, "b", bar), settings)
