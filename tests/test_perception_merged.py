"""Fresco pieces of one colour closer than a millimetre: one blob in the mask, each measured on its free edges.

Synthetic frames of two neighbouring pieces of a fracture, one moved towards the other until
their gap is under the two pixels the mask's morphology closes. Where the image shows the gap (no
blur: a line of pixels off the colour), the mask is cut along it and each piece is a whole face.
Where a blur hides it, the faces are one blob: looked for around its expected place (a region of
interest, as Inspect looks at a target), or anywhere (Detect before picking),
each piece is registered into the merged blob on the edges the blob's contour follows; an
outline that does not lie in the blob there is not found. A whole slab laid out with
sub-millimetre gaps: every piece is found where it lies, or said to be ambiguous; none is
found anywhere else.
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


def two_pieces(seed: int, slab_yaw_deg: float, gap_mm: float, blur_px: float):
    a, b = neighbours(seed, math.radians(slab_yaw_deg))
    ax, ay = moved_towards(a, b, gap_mm / 1000)
    frame = render_frame(
        [SyntheticPrism("red", ax, ay, a.yaw_rad, a.prism), SyntheticPrism("red", b.x_m, b.y_m, b.yaw_rad, b.prism)],
        blur_sigma_px=blur_px,
    )
    return frame, ((a, (ax, ay)), (b, (b.x_m, b.y_m)))


CASES = [(3, 0.0, 0.8), (0, 0.0, 0.5), (1, 40.0, 0.7), (2, 20.0, 0.6)]


@pytest.mark.parametrize(("seed", "slab_yaw_deg", "gap_mm"), CASES)
def test_each_of_two_merged_pieces_is_measured_on_its_free_edges_within_a_tenth(seed, slab_yaw_deg, gap_mm) -> None:
    frame, pieces = two_pieces(seed, slab_yaw_deg, gap_mm, blur_px=1.0)
    for piece, (x, y) in pieces:
        # Looked for at its target (where it belongs), as Inspect does, and anywhere, as Detect does.
        for around in ((piece.x_m, piece.y_m), None):
            detection = look_for(frame, piece, around)
            assert detection.found, detection.reason
            assert "free edges" in detection.reason and detection.merged
            if around is None:
                assert "one of a blob as large as" in detection.reason
            pose = detection.pose_world
            assert 1000 * math.hypot(pose.x_m - x, pose.y_m - y) < 0.1
            assert abs(math.degrees(math.remainder(pose.yaw_rad - piece.yaw_rad, 2 * math.pi))) < 0.1


@pytest.mark.parametrize(("seed", "slab_yaw_deg", "gap_mm"), CASES)
def test_a_gap_the_image_shows_cuts_the_faces_apart(seed, slab_yaw_deg, gap_mm) -> None:
    frame, pieces = two_pieces(seed, slab_yaw_deg, gap_mm, blur_px=0.0)
    for piece, (x, y) in pieces:
        detection = look_for(frame, piece, None)
        assert detection.found, detection.reason
        assert "free edges" not in detection.reason and not detection.merged  # a whole face of its own
        assert len(detection.candidates_xy_m) == 2  # two blobs
        assert 1000 * math.hypot(detection.pose_world.x_m - x, detection.pose_world.y_m - y) < 0.1


def test_an_outline_that_does_not_lie_in_the_merged_blob_there_is_not_found() -> None:
    frame, ((a, _), (b, _)) = two_pieces(3, 0.0, 0.6, blur_px=1.0)
    # Piece a's outline looked for at piece b's place: nothing there is a.
    detection = look_for(frame, a, (b.x_m, b.y_m))
    assert not detection.found and detection.status is DetectionStatus.AMBIGUOUS, detection.reason


@pytest.mark.parametrize("blur_px", [0.0, 1.0])
@pytest.mark.parametrize("seed", [3])
def test_a_slab_laid_out_with_sub_millimetre_gaps_shows_where_each_piece_is_or_says_it_cannot(
    monkeypatch, seed: int, blur_px: float
) -> None:
    import bt_arrange.shapes.fracture as fracture_module
    from bt_arrange.shapes.fracture import fracture

    monkeypatch.setattr(fracture_module, "MIN_GAP_M", 0.0)
    pieces = fracture((0.16, 0.12, 0.02), 6, 0.0006, seed, pose=(0.5, 0.0, 0.3))
    frame = render_frame(
        [SyntheticPrism("red", p.x_m, p.y_m, p.yaw_rad, p.prism) for p in pieces], blur_sigma_px=blur_px
    )
    found = 0
    for piece in pieces:
        detection = look_for(frame, piece, None)
        if detection.found:
            found += 1
            error_mm = 1000 * math.hypot(detection.pose_world.x_m - piece.x_m, detection.pose_world.y_m - piece.y_m)
            assert error_mm < 0.1, (piece.index, error_mm, detection.reason)
        else:
            # The two middle pieces' free edges hold too little of them to tell where they are.
            assert detection.status in (DetectionStatus.AMBIGUOUS, DetectionStatus.PARTIAL), detection.reason
    assert found >= 3


def test_a_piece_cut_by_the_image_border_stays_partial_even_where_it_is_expected() -> None:
    a, _ = neighbours(3)
    y_m = 0.475  # the image spans y to 0.476 m at the top faces' height: the border cuts the piece in half
    frame = render_frame([SyntheticPrism("red", a.x_m, y_m, a.yaw_rad, a.prism)])
    detection = look_for(frame, a, (a.x_m, y_m))
    assert detection.status is DetectionStatus.PARTIAL, detection.reason
    assert "cut by the image border" in detection.reason


def test_a_merged_face_seen_again_is_registered_once_to_the_same_pose() -> None:
    from bt_arrange.perception import outline_merged

    frame, pieces = two_pieces(0, 0.0, 0.5, blur_px=1.0)
    piece, _ = pieces[0]
    outline_merged._FREE_POSES._results.clear()
    first = look_for(frame, piece, (piece.x_m, piece.y_m))
    hits = outline_merged._FREE_POSES.hits
    again = look_for(frame, piece, (piece.x_m, piece.y_m))
    assert outline_merged._FREE_POSES.hits > hits  # the second look's contour registration was kept
    outline_merged._FREE_POSES._results.clear()
    fresh = look_for(frame, piece, (piece.x_m, piece.y_m))
    assert first.found and first.merged
    poses = [(d.pose_world.x_m, d.pose_world.y_m, d.pose_world.yaw_rad) for d in (first, again, fresh)]
    assert poses[0] == poses[1] == poses[2]
    assert first.reprojection_error_px == again.reprojection_error_px == fresh.reprojection_error_px


def test_the_memo_keeps_the_latest_results_and_keys_arrays_by_value() -> None:
    import numpy as np

    from bt_arrange.perception.memo import Memo, array_key

    memo = Memo(size=2)
    calls = []
    for key in ("a", "b", "a", "c", "a"):
        memo.get(key, lambda key=key: calls.append(key) or key.upper())
    assert calls == ["a", "b", "c", "a"]  # "a" kept until "c" pushed it out
    assert array_key(np.array([1.0, 2.0])) == array_key(np.array([1.0, 2.0]))
    assert array_key(np.array([1.0, 2.0])) != array_key(np.array([1.0, 2.0 + 1e-15]))
    assert array_key(np.zeros((2, 1))) != array_key(np.zeros((1, 2)))
