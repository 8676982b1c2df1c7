"""Sub-pixel corners on anti-aliased synthetic frames, and the comparison that chose the method."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bt_arrange.perception import DEFAULT_COLOUR_TABLE
from bt_arrange.perception.corners import (
    chroma,
    refine_contour_lines,
    refine_corner_subpix,
    refine_edge_lines,
)
from bt_arrange.perception.segmentation import (
    approximate_quadrilateral,
    colour_mask,
    largest_contour,
    order_corners,
)
from bt_arrange.perception.synthetic import (
    SIM_SIDE_RGB,
    SIM_TABLE_RGB,
    SyntheticCube,
    project_points,
    render_frame,
    sim_intrinsics,
    top_down_camera_pose,
)
from bt_arrange.robot import CameraFrame

INTRINSICS = sim_intrinsics()
CAMERA = top_down_camera_pose()

# A spread over the image: centre, corners of the visible table, all lightings, yaws from
# square to the image to 45 degrees.
CUBES = [
    SyntheticCube("red", 0.50, 0.00, math.radians(7.0), 1.0),
    SyntheticCube("green", 0.68, 0.38, math.radians(-33.0), 0.45),
    SyntheticCube("blue", 0.33, -0.40, math.radians(45.0), 0.7),
    SyntheticCube("yellow", 0.36, 0.31, math.radians(18.0), 0.55),
    SyntheticCube("red", 0.66, -0.22, math.radians(-3.0), 0.85),
    SyntheticCube("blue", 0.52, 0.15, math.radians(61.0), 0.5),
]


def pixel_corners(frame: CameraFrame, colour: str) -> tuple[np.ndarray, np.ndarray]:
    """The pipeline's pixel-level corners and the contour they came from."""
    contour = largest_contour(colour_mask(frame.rgb, DEFAULT_COLOUR_TABLE[colour]))
    assert contour is not None
    polygon = order_corners(approximate_quadrilateral(contour))
    return refine_contour_lines(contour, polygon), contour


def corner_error_px(found: np.ndarray, cube: SyntheticCube) -> float:
    truth = project_points(INTRINSICS, CAMERA, cube.top_corners_world())
    return float(np.linalg.norm(found[:, None] - truth[None], axis=2).min(axis=1).max())


@pytest.fixture(scope="module")
def frames() -> list[CameraFrame]:
    return [render_frame([cube], INTRINSICS, CAMERA, supersample=8) for cube in CUBES]


def test_grey_has_no_chroma_and_mixes_stay_linear() -> None:
    greys = np.array([SIM_SIDE_RGB, SIM_TABLE_RGB, (0.1, 0.1, 0.1)]) * 255
    assert np.abs(chroma(greys)).max() < 0.03 * 255
    red, table = np.array([204.0, 20.0, 20.0]), np.array(SIM_TABLE_RGB) * 255
    mix = 0.3 * red + 0.7 * table
    assert np.allclose(chroma(mix), 0.3 * chroma(red) + 0.7 * chroma(table))


def test_edge_lines_bring_corners_within_a_tenth_of_a_pixel(frames: list[CameraFrame]) -> None:
    for cube, frame in zip(CUBES, frames, strict=True):
        start, _ = pixel_corners(frame, cube.colour)
        refined = refine_edge_lines(frame.rgb, start)
        assert refined is not None
        assert corner_error_px(refined, cube) < 0.1, cube


def test_edge_lines_converge_from_a_pixel_away(frames: list[CameraFrame]) -> None:
    cube, frame = CUBES[1], frames[1]
    truth = order_corners(project_points(INTRINSICS, CAMERA, cube.top_corners_world()))
    rng = np.random.default_rng(0)
    start = truth + rng.uniform(-1.0, 1.0, truth.shape)
    refined = refine_edge_lines(frame.rgb, start)
    assert refined is not None
    assert corner_error_px(refined, cube) < 0.1


def test_edge_lines_with_the_sims_realistic_camera_noise() -> None:
    # CameraNoiseConfig.realistic: sigma 4 grey levels, 0.8 px blur.
    for seed, cube in enumerate(CUBES[:3]):
        frame = render_frame([cube], INTRINSICS, CAMERA, noise_sigma=4.0, blur_sigma_px=0.8, seed=seed)
        start, _ = pixel_corners(frame, cube.colour)
        refined = refine_edge_lines(frame.rgb, start)
        assert refined is not None
        assert corner_error_px(refined, cube) < 0.25, cube


def test_edge_lines_are_the_most_accurate_method(frames: list[CameraFrame]) -> None:
    """The measurement behind the default: fitted sub-pixel edges beat the alternatives."""
    errors: dict[str, list[float]] = {"edge_lines": [], "corner_subpix": [], "contour_lines": []}
    for cube, frame in zip(CUBES, frames, strict=True):
        start, _ = pixel_corners(frame, cube.colour)
        refined = refine_edge_lines(frame.rgb, start)
        assert refined is not None
        errors["edge_lines"].append(corner_error_px(refined, cube))
        errors["corner_subpix"].append(corner_error_px(refine_corner_subpix(frame.rgb, start), cube))
        errors["contour_lines"].append(corner_error_px(start, cube))
    means = {name: float(np.mean(values)) for name, values in errors.items()}
    assert means["edge_lines"] < 0.05
    assert means["edge_lines"] < 0.25 * means["corner_subpix"]
    assert means["edge_lines"] < 0.25 * means["contour_lines"]


def test_aliased_render_keeps_corners_within_half_a_pixel() -> None:
    # TinyRenderer samples pixel centres without anti-aliasing: an edge square to the image
    # axes can only be placed to the pixel boundary, +-0.5 px.
    for cube in (CUBES[0], CUBES[2], SyntheticCube("yellow", 0.55, 0.1, 0.0)):
        frame = render_frame([cube], INTRINSICS, CAMERA, supersample=1)
        start, _ = pixel_corners(frame, cube.colour)
        refined = refine_edge_lines(frame.rgb, start)
        assert refined is not None
        assert corner_error_px(refined, cube) < 0.75, cube


def test_edge_lines_unmix_a_touching_cube_of_another_colour() -> None:
    # Two faces share an edge: each side of it is unmixed with the neighbour's own colour.
    red = SyntheticCube("red", 0.5, 0.0, 0.0, 0.9)
    yellow = SyntheticCube("yellow", 0.5, 0.05, 0.0, 0.6)
    frame = render_frame([red, yellow], INTRINSICS, CAMERA)
    for cube in (red, yellow):
        start, _ = pixel_corners(frame, cube.colour)
        refined = refine_edge_lines(frame.rgb, start)
        assert refined is not None
        assert corner_error_px(refined, cube) < 0.1, cube.colour


def test_the_corner_fit_median_and_cross_product_are_numpys_exactly() -> None:
    # corners.py avoids np.median (its first call imports numpy.ma) and np.cross (slow on
    # 3-vectors): the results must be numpy's, bit for bit, or the benchmark figures would move.
    from bt_arrange.perception.corners import _cross, _median

    rng = np.random.default_rng(0)
    for count in range(1, 40):
        for shape, axis in (((count,), None), ((count, 2), 0)):
            values = rng.normal(size=shape) * 10 ** rng.uniform(-3, 3)
            assert np.array_equal(_median(values, axis=axis), np.median(values, axis=axis))
    assert np.isnan(_median(np.array([1.0, np.nan, 2.0])))
    for _ in range(200):
        a, b = rng.normal(size=3) * 100, rng.normal(size=3)
        assert np.array_equal(_cross(a, b), np.cross(a, b))


def test_edge_lines_count_a_grey_side_strip_before_a_coloured_face_as_outside() -> None:
    # A raised part's face (blue), its side seen as a grey strip 2 px wide, and a red face of the
    # layer below beyond it: the strip is no mix of blue and red, so it counts as outside and
    # the edge stays at the face's own pixels (unmixed from red, the edge was a pixel too far).
    rgb = np.zeros((200, 300, 3), dtype=np.uint8)
    rgb[:] = SIM_TABLE_RGB
    rgb[20:48, 30:270] = (198, 19, 19)
    rgb[48:50, 50:251] = (150, 150, 146)
    rgb[50:151, 50:251] = (24, 61, 210)
    truth = np.array([[49.5, 49.5], [250.5, 49.5], [250.5, 150.5], [49.5, 150.5]])
    refined = refine_edge_lines(rgb, truth + np.array([[0.3, -0.3], [-0.3, -0.3], [-0.3, 0.3], [0.3, 0.3]]))
    assert refined is not None
    assert float(np.abs(refined - truth).max()) < 0.1, refined


def test_edge_lines_keep_each_pixel_s_coverage_within_itself_beside_a_twin_across_a_narrow_gap() -> None:
    # A green face, a 1 mm gap (2 px: the red face below, anti-aliased at both ends) and its green
    # twin beyond: an outside colour read on the mix before the twin gave the gap's pixels negative
    # coverages and pulled the edge inwards (0.15 mm on the pyramid's green 2 in MuJoCo).
    green, red = np.array((25, 160, 49), dtype=float), np.array((197, 20, 20), dtype=float)
    rgb = np.zeros((200, 300, 3), dtype=np.uint8)
    rgb[:] = SIM_TABLE_RGB
    rgb[30:171, 150:156] = red
    rgb[50:151, 50:150] = green
    rgb[50:151, 150] = np.round(0.25 * green + 0.75 * red)
    rgb[50:151, 152] = np.round(0.5 * green + 0.5 * red)
    rgb[50:151, 153:260] = green
    truth = np.array([[49.5, 49.5], [149.75, 49.5], [149.75, 150.5], [49.5, 150.5]])
    refined = refine_edge_lines(rgb, truth + np.array([[0.3, -0.3], [-0.3, -0.3], [-0.3, 0.3], [0.3, 0.3]]))
    assert refined is not None
    assert float(np.abs(refined - truth).max()) < 0.1, refined
