"""Segmentation stages against known answers: mask, morphology, blobs, polygon, corner order."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from bt_arrange.perception import DEFAULT_COLOUR_TABLE
from bt_arrange.perception.corners import refine_contour_lines
from bt_arrange.perception.segmentation import (
    approximate_quadrilateral,
    clean_mask,
    colour_mask,
    find_blobs,
    largest_contour,
    order_corners,
    outline_deviation_px,
)
from bt_arrange.perception.synthetic import (
    SyntheticCube,
    project_points,
    render_frame,
    sim_intrinsics,
    top_down_camera_pose,
)

INTRINSICS = sim_intrinsics()
CAMERA = top_down_camera_pose()


def signed_distance_px(points: np.ndarray, polygon: np.ndarray) -> np.ndarray:
    """Signed distance of points (Nx2) to a convex polygon: positive inside."""
    area2 = np.sum(polygon[:, 0] * np.roll(polygon[:, 1], -1) - np.roll(polygon[:, 0], -1) * polygon[:, 1])
    sign = 1.0 if area2 > 0 else -1.0
    distances = []
    for a, b in zip(polygon, np.roll(polygon, -1, axis=0), strict=True):
        edge = (b - a) / np.linalg.norm(b - a)
        distances.append(sign * (edge[0] * (points[:, 1] - a[1]) - edge[1] * (points[:, 0] - a[0])))
    return np.min(distances, axis=0)


def true_corners(cube: SyntheticCube) -> np.ndarray:
    return order_corners(project_points(INTRINSICS, CAMERA, cube.top_corners_world()))


def nearest_error_px(found: np.ndarray, truth: np.ndarray) -> float:
    return float(np.linalg.norm(found[:, None] - truth[None], axis=2).min(axis=1).max())


@pytest.mark.parametrize("yaw_deg, brightness", [(20.0, 0.6), (45.0, 1.0)])
def test_mask_is_the_face_away_from_its_edges(yaw_deg: float, brightness: float) -> None:
    cube = SyntheticCube("red", 0.62, 0.25, math.radians(yaw_deg), brightness)
    frame = render_frame([cube], INTRINSICS, CAMERA)
    mask = colour_mask(frame.rgb, DEFAULT_COLOUR_TABLE["red"])
    truth = true_corners(cube)
    x0, y0 = np.floor(truth.min(axis=0)).astype(int) - 60
    x1, y1 = np.ceil(truth.max(axis=0)).astype(int) + 60
    v, u = np.mgrid[y0:y1, x0:x1]
    distance = signed_distance_px(np.column_stack([u.ravel(), v.ravel()]).astype(float), truth)
    crop = mask[y0:y1, x0:x1].ravel()
    inside, outside = distance > 1.5, distance < -1.5
    assert np.all(crop[inside] == 255)
    # Outside: the white cube sides, the grey table, and the rest of the image.
    assert np.all(crop[outside] == 0)
    assert np.count_nonzero(mask) == np.count_nonzero(crop)
    assert inside.sum() > 10000


def test_closing_and_opening_fill_holes_and_remove_specks() -> None:
    mask = np.zeros((200, 200), dtype=np.uint8)
    mask[50:150, 50:150] = 255
    mask[90:93, 100:103] = 0  # a hole, as a specular highlight would make
    mask[10:13, 10:13] = 255  # a speck of noise
    cleaned = clean_mask(mask)
    assert cleaned[91, 101] == 255
    assert cleaned[11, 11] == 0
    # The square's straight sides stay where they were.
    assert cleaned[100, 50] == 255 and cleaned[100, 49] == 0 and cleaned[100, 149] == 255


def test_blobs_on_a_downscaled_mask_map_back_to_full_resolution() -> None:
    mask = np.zeros((1080, 1920), dtype=np.uint8)
    mask[300:400, 1000:1110] = 255  # 110 x 100 px, centre (1054.5, 349.5)
    mask[700:705, 200:205] = 255  # a speck, below any face's area
    scale = 4
    small = cv2.resize(mask, (1920 // scale, 1080 // scale), interpolation=cv2.INTER_AREA)
    blobs = find_blobs((small > 127).astype(np.uint8) * 255, scale, min_area_px=2000.0)
    assert len(blobs) == 1
    blob = blobs[0]
    assert blob.area_px == pytest.approx(11000.0, rel=0.05)
    assert blob.centroid_px == pytest.approx((1054.5, 349.5), abs=1.0)
    x, y, w, h = blob.bbox_px
    assert (x, y, x + w, y + h) == (1000, 300, 1112, 400)


@pytest.mark.parametrize("yaw_deg", [0.0, 10.0, 30.0, 44.0, 45.0])
def test_polygon_has_four_corners_and_contour_lines_place_them_within_a_pixel(yaw_deg: float) -> None:
    cube = SyntheticCube("blue", 0.45, -0.2, math.radians(yaw_deg), 0.8)
    frame = render_frame([cube], INTRINSICS, CAMERA)
    contour = largest_contour(colour_mask(frame.rgb, DEFAULT_COLOUR_TABLE["blue"]))
    assert contour is not None
    polygon = approximate_quadrilateral(contour)
    assert len(polygon) == 4
    truth = true_corners(cube)
    # Douglas-Peucker vertices sit on the mask's corners, rounded by the 7x7 opening.
    assert nearest_error_px(polygon.astype(float), truth) < 3.5
    # Lines through each side's contour pixels meet within a pixel of the true corners.
    corners = refine_contour_lines(contour, order_corners(polygon))
    assert nearest_error_px(corners, truth) < 1.0


def test_corners_are_ordered_clockwise_on_screen_from_the_top_left() -> None:
    square = np.array([[10.0, 10.0], [20.0, 10.0], [20.0, 20.0], [10.0, 20.0]])
    rng = np.random.default_rng(3)
    for _ in range(5):
        shuffled = square[rng.permutation(4)]
        assert np.array_equal(order_corners(shuffled), square)
    diamond = np.array([[15.0, 5.0], [25.0, 15.0], [15.0, 25.0], [5.0, 15.0]])
    ordered = order_corners(diamond[::-1])
    # Clockwise on screen (y down) is a positive shoelace sum.
    area2 = np.sum(ordered[:, 0] * np.roll(ordered[:, 1], -1) - np.roll(ordered[:, 0], -1) * ordered[:, 1])
    assert area2 > 0
    assert set(map(tuple, ordered)) == set(map(tuple, diamond))


def test_outline_deviation_measures_how_far_a_contour_leaves_its_quadrilateral() -> None:
    square = np.array([[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0]])
    on_sides = np.array([[5, 0], [10, 3], [4, 10], [0, 7], [0, 0]])
    assert outline_deviation_px(on_sides, square) == pytest.approx(0.0)
    notch = np.vstack([on_sides, [[3, 3]]])  # a notch 3 px deep into a corner
    assert outline_deviation_px(notch, square) == pytest.approx(3.0)
