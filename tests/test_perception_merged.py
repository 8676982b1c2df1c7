"""Fresco pieces of one colour closer than a millimetre: one blob in the mask, each measured on its free edges.

Synthetic frames of two neighbouring pieces of a fracture, one moved towards the other until
their gap is under the two pixels the mask's morphology closes. Looked for around its expected
place (a region of interest, as Inspect looks at a target), each piece is registered into the
merged blob on the edges the blob's contour follows; without an expected place the blob stays
ambiguous, and an outline that does not lie in the blob there is not found.
"""

from __future__ import annotations

import math

import pytest
from merged_pieces import moved_towards, neighbours

from bt_arrange.objects import ObjectType
from bt_arrange.perception import DetectionStatus, PartDetector, WorldRegion
from bt_arrange.perception.synthetic import SyntheticPrism, render_frame
from bt_arrange.shapes.fracture import Piece

REGION_HALF_M = 0.05


def look_for(frame, piece: Piece, around_xy_m: tuple[float, float] | None):
    kind = ObjectType(f"tile {piece.index}", shape=piece.prism)
    roi = None if around_xy_m is None else WorldRegion.around(*around_xy_m, REGION_HALF_M)
    return PartDetector().for_object(kind).detect(frame, "red", roi=roi)


@pytest.mark.parametrize(("seed", "slab_yaw_deg", "gap_mm"), [(3, 0.0, 0.8), (0, 0.0, 0.5), (1, 40.0, 0.7)])
def test_each_of_two_merged_pieces_is_measured_on_its_free_edges_within_a_tenth(seed, slab_yaw_deg, gap_mm) -> None:
    a, b = neighbours(seed, math.radians(slab_yaw_deg))
    ax, ay = moved_towards(a, b, gap_mm / 1000)
    frame = render_frame(
        [SyntheticPrism("red", ax, ay, a.yaw_rad, a.prism), SyntheticPrism("red", b.x_m, b.y_m, b.yaw_rad, b.prism)]
    )
    whole = look_for(frame, a, None)
    assert whole.status is DetectionStatus.AMBIGUOUS, "the two faces are one blob in the mask"
    for piece, (x, y) in ((a, (ax, ay)), (b, (b.x_m, b.y_m))):
        # Looked for at its target (where it belongs), as Inspect does: the moved piece lies ~1 mm off it.
        detection = look_for(frame, piece, (piece.x_m, piece.y_m))
        assert detection.found, detection.reason
        assert "free edges" in detection.reason
        pose = detection.pose_world
        assert 1000 * math.hypot(pose.x_m - x, pose.y_m - y) < 0.1
        assert abs(math.degrees(math.remainder(pose.yaw_rad - piece.yaw_rad, 2 * math.pi))) < 0.1


def test_an_outline_that_does_not_lie_in_the_merged_blob_there_is_not_found() -> None:
    a, b = neighbours(3)
    ax, ay = moved_towards(a, b, 0.0006)
    frame = render_frame(
        [SyntheticPrism("red", ax, ay, a.yaw_rad, a.prism), SyntheticPrism("red", b.x_m, b.y_m, b.yaw_rad, b.prism)]
    )
    # Piece a's outline looked for at piece b's place: nothing there is a.
    detection = look_for(frame, a, (b.x_m, b.y_m))
    assert not detection.found and detection.status is DetectionStatus.AMBIGUOUS, detection.reason


def test_a_piece_cut_by_the_image_border_stays_partial_even_where_it_is_expected() -> None:
    a, _ = neighbours(3)
    y_m = 0.475  # the image spans y to 0.476 m at the top faces' height: the border cuts the piece in half
    frame = render_frame([SyntheticPrism("red", a.x_m, y_m, a.yaw_rad, a.prism)])
    detection = look_for(frame, a, (a.x_m, y_m))
    assert detection.status is DetectionStatus.PARTIAL, detection.reason
    assert "cut by the image border" in detection.reason
