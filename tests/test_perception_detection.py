"""The detector's outcomes: FOUND, NOT_FOUND, AMBIGUOUS, PARTIAL, and the edge cases behind them."""

from __future__ import annotations

import math
import time
from dataclasses import replace

import numpy as np
import pytest

from bt_arrange.errors import OutOfRangeError, PerceptionError
from bt_arrange.geometry import fold_yaw
from bt_arrange.perception import (
    DEFAULT_COLOUR_TABLE,
    ColourRange,
    Detection,
    DetectionStatus,
    DetectorConfig,
    PartDetector,
    PoseModel,
    WorldRegion,
)
from bt_arrange.perception.synthetic import (
    SIM_PART_COLOURS_RGB,
    SyntheticCube,
    project_points,
    render_frame,
    sim_intrinsics,
    top_down_camera_pose,
)
from bt_arrange.robot import CameraFrame, PixelWindow

INTRINSICS = sim_intrinsics()
CAMERA = top_down_camera_pose()
DETECTOR = PartDetector()


def assert_found_at(detection: Detection, cube: SyntheticCube, xy_mm: float = 0.2, yaw_deg: float = 0.3) -> None:
    assert detection.status is DetectionStatus.FOUND, detection.reason
    assert detection.pose_world is not None
    error_mm = 1000.0 * math.hypot(detection.pose_world.x_m - cube.x_m, detection.pose_world.y_m - cube.y_m)
    assert error_mm < xy_mm, detection.reason
    assert abs(math.degrees(fold_yaw(detection.pose_world.yaw_rad - cube.yaw_rad))) < yaw_deg


def test_found_cube_has_a_pose_and_quality_figures() -> None:
    cube = SyntheticCube("green", 0.58, -0.17, math.radians(23.0), 0.6)
    detection = DETECTOR.detect(render_frame([cube], INTRINSICS, CAMERA), "green")
    assert_found_at(detection, cube)
    assert detection.found and detection.reason.startswith("green part at x=0.58")
    assert detection.pose_world is not None and detection.planar is not None
    assert detection.pose_world.z_m == pytest.approx(0.025)  # the centre, half an edge below the top
    assert detection.planar.x_m == pytest.approx(cube.x_m, abs=2e-4)
    assert detection.reprojection_error_px is not None and detection.reprojection_error_px < 0.1
    assert detection.area_px is not None and detection.expected_area_px is not None
    assert detection.area_px / detection.expected_area_px == pytest.approx(1.0, abs=0.05)
    assert detection.edge_m == pytest.approx(0.05, rel=0.005)
    assert detection.corners_px is not None and detection.corners_px.shape == (4, 2)
    # The paper's 6-DoF PnP pose is reported too, and agrees with a cube lying flat.
    assert detection.pnp_pose_world is not None and detection.tilt_deg is not None
    assert detection.tilt_deg < 0.5
    assert detection.pnp_pose_world.z_m == pytest.approx(0.025, abs=0.002)


def test_empty_table_is_not_found() -> None:
    frame = render_frame([], INTRINSICS, CAMERA)
    for colour, detection in DETECTOR.detect_all(frame).items():
        assert detection.status is DetectionStatus.NOT_FOUND
        assert detection.pose_world is None
        assert f"no {colour} blob" in detection.reason


def test_specks_of_colour_are_ignored() -> None:
    cube = SyntheticCube("red", 0.5, 0.1, 0.3)
    frame = render_frame([cube], INTRINSICS, CAMERA)
    rgb = frame.rgb.copy()
    rgb[100:104, 200:204] = (200, 20, 20)  # a red speck of 16 px, as a reflection could make
    rgb[900:920, 1500:1510] = (200, 20, 20)  # and a red scrap of 200 px
    detection = DETECTOR.detect(replace(frame, rgb=rgb), "red")
    assert_found_at(detection, cube)


def test_two_cubes_of_one_colour_are_ambiguous() -> None:
    cubes = [SyntheticCube("blue", 0.45, 0.2, 0.1), SyntheticCube("blue", 0.6, -0.25, -0.4)]
    detection = DETECTOR.detect(render_frame(cubes, INTRINSICS, CAMERA), "blue")
    assert detection.status is DetectionStatus.AMBIGUOUS
    assert detection.pose_world is None
    assert "2 blue blobs" in detection.reason
    found = sorted(detection.candidates_xy_m)
    expected = sorted((c.x_m, c.y_m) for c in cubes)
    assert np.allclose(found, expected, atol=0.005)


def test_two_touching_cubes_of_one_colour_are_ambiguous() -> None:
    cubes = [SyntheticCube("yellow", 0.5, 0.0, 0.0), SyntheticCube("yellow", 0.5, 0.05, 0.0)]
    detection = DETECTOR.detect(render_frame(cubes, INTRINSICS, CAMERA), "yellow")
    assert detection.status is DetectionStatus.AMBIGUOUS
    assert "2.0 faces" in detection.reason


@pytest.mark.parametrize("y_m", [-0.46, -0.435])
def test_cube_cut_by_the_image_border_is_partial(y_m: float) -> None:
    # Image right is world -y; at the top faces' height the image ends at y = -0.455 m. At
    # -0.435 only the face's last 5 mm (10 px) are cut off.
    cube = SyntheticCube("red", 0.5, y_m, 0.0)
    corners_px = project_points(INTRINSICS, CAMERA, cube.top_corners_world())
    assert corners_px[:, 0].max() > INTRINSICS.width_px  # the set-up: the face is cut
    detection = DETECTOR.detect(render_frame([cube], INTRINSICS, CAMERA), "red")
    assert detection.status is DetectionStatus.PARTIAL
    assert "cut by the image border" in detection.reason
    assert detection.pose_world is None


def test_cube_just_inside_the_border_is_found() -> None:
    cube = SyntheticCube("red", 0.5, -0.423, 0.0)
    corners_px = project_points(INTRINSICS, CAMERA, cube.top_corners_world())
    assert INTRINSICS.width_px - 25 < corners_px[:, 0].max() < INTRINSICS.width_px
    assert_found_at(DETECTOR.detect(render_frame([cube], INTRINSICS, CAMERA), "red"), cube)


def covered(frame: CameraFrame, box_px: tuple[int, int, int, int]) -> CameraFrame:
    """The frame with a dark grey box (a gripper finger, say) painted over ``(x0, y0, x1, y1)``."""
    rgb = frame.rgb.copy()
    x0, y0, x1, y1 = box_px
    rgb[y0:y1, x0:x1] = (40, 40, 42)
    return replace(frame, rgb=rgb)


@pytest.mark.parametrize(
    "which, reason",
    [
        ("a third", "blob is 70% of a face"),
        ("a corner", "not a square face"),
        ("a notch at a corner", "outline strays 6.2 px from a quadrilateral"),
    ],
)
def test_covered_cube_is_partial(which: str, reason: str) -> None:
    cube = SyntheticCube("green", 0.5, 0.0, math.radians(10.0))
    frame = render_frame([cube], INTRINSICS, CAMERA)
    corners_px = project_points(INTRINSICS, CAMERA, cube.top_corners_world())
    (u0, v0), (u1, v1) = corners_px.min(axis=0).astype(int), corners_px.max(axis=0).astype(int)
    u, v = corners_px[np.argmin(corners_px.sum(axis=1))].astype(int)
    box = {
        "a third": (u0 - 10, v0 - 10, u0 + (u1 - u0) // 3, v1 + 10),
        "a corner": (u - 30, v - 30, u + 25, v + 25),
        "a notch at a corner": (u - 8, v - 8, u + 9, v + 9),
    }[which]
    detection = DETECTOR.detect(covered(frame, box), "green")
    assert detection.status is DetectionStatus.PARTIAL, detection.reason
    assert detection.pose_world is None
    assert detection.reason.startswith("green ") and reason in detection.reason


@pytest.mark.parametrize("yaw_deg", [45.0, 44.5, -45.5, 135.0])
def test_cube_turned_near_45_degrees(yaw_deg: float) -> None:
    cube = SyntheticCube("blue", 0.42, 0.22, math.radians(yaw_deg), 0.5)
    detection = DETECTOR.detect(render_frame([cube], INTRINSICS, CAMERA), "blue")
    assert_found_at(detection, cube)
    assert detection.pose_world is not None
    assert -45.0 <= math.degrees(detection.pose_world.yaw_rad) < 45.0


def test_touching_cubes_of_different_colours_are_all_found() -> None:
    cubes = [
        SyntheticCube("red", 0.50, 0.00, 0.0, 0.9),
        SyntheticCube("blue", 0.50, 0.05, 0.0, 0.6),  # shares the red face's edge
        SyntheticCube("yellow", 0.55, 0.00, 0.0, 0.5),  # shares the red face's other edge
        SyntheticCube("green", 0.3553, 0.2, math.radians(45.0)),
        SyntheticCube("red", 0.3553 + 0.05 * math.sqrt(2) / 2 + 0.025, 0.2, 0.0),  # touches green's tip
    ]
    frame = render_frame(cubes, INTRINSICS, CAMERA)
    detections = DETECTOR.detect_all(frame, roi=WorldRegion(0.45, 0.6, -0.1, 0.1))
    for cube in cubes[:3]:
        assert_found_at(detections[cube.colour], cube)
    assert_found_at(DETECTOR.detect(frame, "green"), cubes[3])


@pytest.mark.parametrize("rgb", [(0.80, 0.08, 0.20), (0.80, 0.08, 0.08), (0.80, 0.20, 0.08)])
def test_red_is_found_on_both_sides_of_hue_zero(rgb: tuple[float, float, float]) -> None:
    # Hues about 351, 0 and 9 degrees: the two ranges of the wrap-around and their seam.
    cube = SyntheticCube("red", 0.47, -0.12, math.radians(-20.0), 0.7, rgb=rgb)
    assert_found_at(DETECTOR.detect(render_frame([cube], INTRINSICS, CAMERA), "red"), cube)


def test_unknown_colour_raises_naming_it_and_the_known_ones() -> None:
    frame = render_frame([SyntheticCube("red", 0.5, 0.0)], INTRINSICS, CAMERA)
    with pytest.raises(PerceptionError) as error:
        DETECTOR.detect(frame, "purple")
    assert "'purple'" in str(error.value)
    assert all(name in str(error.value) for name in DEFAULT_COLOUR_TABLE)


def test_an_extended_colour_table_finds_the_new_colour() -> None:
    orange_rgb = (1.0, 0.5, 0.0)
    cube = SyntheticCube("orange", 0.52, 0.08, 0.3, 0.8, rgb=orange_rgb)
    frame = render_frame([cube, SyntheticCube("red", 0.4, -0.2)], INTRINSICS, CAMERA)
    detector = PartDetector(DEFAULT_COLOUR_TABLE.with_colour(ColourRange.around_rgb("orange", orange_rgb)))
    assert_found_at(detector.detect(frame, "orange"), cube)
    # Orange (hue 30) is kept apart from red and yellow.
    assert detector.detect(frame, "red").found
    assert detector.detect(frame, "yellow").status is DetectionStatus.NOT_FOUND


def test_region_of_interest_picks_one_of_two_cubes() -> None:
    cubes = [SyntheticCube("red", 0.45, 0.2, 0.1), SyntheticCube("red", 0.6, -0.25, -0.4)]
    frame = render_frame(cubes, INTRINSICS, CAMERA)
    assert DETECTOR.detect(frame, "red").status is DetectionStatus.AMBIGUOUS
    assert_found_at(DETECTOR.detect(frame, "red", roi=WorldRegion.around(0.6, -0.25, 0.05)), cubes[1])
    nothing = DETECTOR.detect(frame, "red", roi=WorldRegion.around(0.3, 0.0, 0.05))
    assert nothing.status is DetectionStatus.NOT_FOUND
    assert "region of interest (2 outside)" in nothing.reason
    with pytest.raises(PerceptionError):
        WorldRegion(0.5, 0.4, 0.0, 0.1)


def test_lifted_cube_is_partial_when_resting_and_found_by_free_pnp() -> None:
    # A cube stacked on another: its top face is at 0.10 m, not 0.05 m.
    cube = SyntheticCube("yellow", 0.5, 0.1, 0.2, table_z_m=0.05)
    frame = render_frame([cube], INTRINSICS, CAMERA)
    resting = DETECTOR.detect(frame, "yellow")
    assert resting.status is DetectionStatus.PARTIAL
    assert "not resting on the table" in resting.reason
    free = PartDetector(config=DetectorConfig(pose_model=PoseModel.FREE)).detect(frame, "yellow")
    assert_found_at(free, cube, xy_mm=1.0)
    assert free.pose_world is not None and free.pose_world.z_m == pytest.approx(0.075, abs=0.002)


def test_image_that_does_not_match_its_intrinsics_raises() -> None:
    frame = render_frame([], INTRINSICS, CAMERA)
    with pytest.raises(PerceptionError, match="1280x720 px but the intrinsics say 1920x1080"):
        DETECTOR.detect(replace(frame, rgb=np.zeros((720, 1280, 3), dtype=np.uint8)), "red")


def test_detection_is_a_pure_function_of_the_frame() -> None:
    frame = render_frame([SyntheticCube("red", 0.5, 0.05, 0.5)], INTRINSICS, CAMERA)
    before = frame.rgb.copy()
    first, second = DETECTOR.detect(frame, "red"), DETECTOR.detect(frame, "red")
    assert np.array_equal(frame.rgb, before)
    assert first.pose_world is not None and second.pose_world is not None
    assert np.array_equal(first.pose_world.matrix, second.pose_world.matrix)
    assert first.reason == second.reason


def test_detect_all_on_four_cubes_and_its_runtime() -> None:
    cubes = [
        SyntheticCube("red", 0.40, 0.25, 0.1, 0.9),
        SyntheticCube("green", 0.62, 0.20, -0.3, 0.5),
        SyntheticCube("blue", 0.38, -0.22, 0.7, 0.7),
        SyntheticCube("yellow", 0.60, -0.30, 0.0, 0.45),
    ]
    frame = render_frame(cubes, INTRINSICS, CAMERA)
    start = time.perf_counter()
    detections = DETECTOR.detect_all(frame)
    elapsed_ms = 1000.0 * (time.perf_counter() - start)
    assert list(detections) == list(DEFAULT_COLOUR_TABLE)
    for cube in cubes:
        assert_found_at(detections[cube.colour], cube)
    # Benchmark-style print, no timed assertion: run pytest -s to see it.
    print(f"\ndetect_all, 4 cubes, 1920x1080: {elapsed_ms:.1f} ms ({elapsed_ms / 4:.1f} ms per cube)")


def test_a_corner_covered_by_a_few_pixels_is_still_found() -> None:
    # The edges are measured away from the corners, so an 11 px box over one corner changes
    # nothing. (This frame once made OpenCV's IPPE return NaN: the detector must survive it.)
    cube = SyntheticCube("green", 0.5, 0.0, math.radians(10.0))
    frame = render_frame([cube], INTRINSICS, CAMERA)
    corners_px = project_points(INTRINSICS, CAMERA, cube.top_corners_world())
    u, v = corners_px[np.argmin(corners_px.sum(axis=1))].astype(int)
    assert_found_at(DETECTOR.detect(covered(frame, (u - 5, v - 5, u + 6, v + 6)), "green"), cube)


def test_clutter_gives_outcomes_never_exceptions() -> None:
    import cv2

    rng = np.random.default_rng(7)
    intrinsics = sim_intrinsics(960, 540)
    for _ in range(6):
        frame = render_frame([], intrinsics, CAMERA, noise_sigma=6.0, seed=int(rng.integers(1000)))
        rgb = frame.rgb.copy()
        for _ in range(12):
            centre = rng.uniform([0, 0], [960, 540])
            points = centre + rng.normal(0.0, rng.uniform(5, 60), (int(rng.integers(3, 8)), 2))
            colour = (np.array(rng.choice(list(SIM_PART_COLOURS_RGB.values()))) * 255 * rng.uniform(0.4, 1.0)).astype(
                int
            )
            cv2.fillPoly(rgb, [points.astype(np.int32)], tuple(int(c) for c in colour))
        for colour, detection in DETECTOR.detect_all(replace(frame, rgb=rgb)).items():
            assert isinstance(detection.status, DetectionStatus)
            assert colour in detection.reason
            assert detection.found == (detection.pose_world is not None)


def test_the_evaluation_shows_a_sign_of_life_before_each_row(monkeypatch, capsys) -> None:
    from bt_arrange.perception import evaluate

    monkeypatch.setattr(evaluate, "make_trials", lambda n, **_: [])
    monkeypatch.setattr(evaluate, "evaluate", lambda trials, detector: type("S", (), {"row": lambda self, r: r})())
    monkeypatch.setattr(evaluate, "runtime_ms", lambda: {})
    evaluate.main(["--trials", "3"])
    lines = capsys.readouterr().err.splitlines()
    assert lines[0] == "evaluate: row 1 of 24, 3 trials: 1920x1080 anti-aliased"
    assert len(lines) == 25 and lines[-1].startswith("evaluate: timing")


# -- windows and the search view -----------------------------------------------------------------


def test_a_windows_intrinsics_move_the_principal_point_and_binning_scales_them() -> None:
    window = PixelWindow(100, 40, 320, 160, binning=4)
    windowed = INTRINSICS.windowed(window)
    assert (windowed.width_px, windowed.height_px) == (80, 40)
    assert windowed.fx_px == pytest.approx(INTRINSICS.fx_px / 4)
    assert windowed.cx_px == pytest.approx((INTRINSICS.cx_px + 0.5 - 100) / 4 - 0.5)
    unbinned = INTRINSICS.windowed(PixelWindow(100, 40, 320, 160))
    assert (unbinned.cx_px, unbinned.cy_px) == pytest.approx((INTRINSICS.cx_px - 100, INTRINSICS.cy_px - 40))


@pytest.mark.parametrize(
    ("arguments", "why"),
    [((-1, 0, 10, 10), "outside"), ((0, 0, 10, 10, 0), "binning"), ((0, 0, 10, 9, 2), "whole number")],
)
def test_a_bad_pixel_window_is_refused_saying_why(arguments, why: str) -> None:
    with pytest.raises(OutOfRangeError, match=why):
        PixelWindow(*arguments)


def test_a_window_leaving_the_image_is_refused() -> None:
    with pytest.raises(OutOfRangeError, match="leaves the"):
        INTRINSICS.windowed(PixelWindow(1900, 0, 40, 40))


def test_locate_finds_every_blob_of_a_colour_in_a_binned_view() -> None:
    cubes = [
        SyntheticCube("red", 0.45, -0.1, 0.2),
        SyntheticCube("red", 0.6, 0.2, 0.9),
        SyntheticCube("blue", 0.5, 0.0),
    ]
    binning = DETECTOR.search_binning(INTRINSICS, CAMERA)
    assert binning == 8
    frame = render_frame(cubes, INTRINSICS.windowed(PixelWindow.full(INTRINSICS, binning)), CAMERA, supersample=2)
    located = sorted(DETECTOR.locate(frame, "red"))
    assert len(located) == 2
    for (x, y), expected in zip(located, [(0.45, -0.1), (0.6, 0.2)], strict=True):
        assert 1000 * math.dist((x, y), expected) < 2.0
    assert DETECTOR.locate(frame, "green") == ()


def test_the_window_around_a_point_holds_its_square_and_stops_at_the_image() -> None:
    window = DETECTOR.window_around(INTRINSICS, CAMERA, 0.5, 0.0, 0.05)
    assert window is not None
    corners = project_points(INTRINSICS, CAMERA, [[0.45, -0.05, 0.05], [0.55, 0.05, 0.05]])
    assert window.x_px <= corners[:, 0].min() and corners[:, 0].max() <= window.x_px + window.width_px
    assert window.y_px <= corners[:, 1].min() and corners[:, 1].max() <= window.y_px + window.height_px
    edge = DETECTOR.window_around(INTRINSICS, CAMERA, 0.5, 0.44, 0.05)
    assert edge is not None and edge.x_px == 0
    assert DETECTOR.window_around(INTRINSICS, CAMERA, 0.5, 2.0, 0.05) is None
