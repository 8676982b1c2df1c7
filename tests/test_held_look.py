"""The held look: a held part measured in the fingers from a frame with depth, the tree and the placing's correction."""

from __future__ import annotations

import math

import cv2
import numpy as np
import py_trees

from bt_arrange.behaviours import LookAtHeld, Place, keys
from bt_arrange.behaviours.held import compose, inverse, look_pose, relative
from bt_arrange.geometry import PlanarPose
from bt_arrange.objects import CUBE, ObjectType
from bt_arrange.paper_cell import camera_pose_world
from bt_arrange.perception.colours import DEFAULT_COLOUR_TABLE
from bt_arrange.perception.held import measure_held
from bt_arrange.perception.outline_fit import OutlineModel, pixels_on_plane
from bt_arrange.plan.layout import Release
from bt_arrange.plan.targets import Target
from bt_arrange.robot import CameraFrame, CameraIntrinsics, PixelWindow
from bt_arrange.shapes import Prism
from bt_arrange.testing.scene import make_context
from bt_arrange.trees.steps import _transfer

PIECE = ObjectType(
    "piece", shape=Prism.from_outline([[0, 0], [0.06, 0], [0.065, 0.03], [0.03, 0.055], [-0.005, 0.035]], 0.02)
)
PLANE_Z_M = 0.1


def _frame(part: PlanarPose, occluder: tuple[float, float, float, float]) -> CameraFrame:
    """A rendered window: the part's top face (red) at ``PLANE_Z_M``, a dark box 3 cm above it, the grey table."""
    T_W_C = camera_pose_world((0.5, 0.0, 0.7), 3.0)
    full = CameraIntrinsics.from_fov(1920, 1080, 70.0)
    window = PixelWindow(100, 250, 420, 420)
    intrinsics = full.windowed(window)
    v, u = np.mgrid[0 : window.height_px, 0 : window.width_px]
    pixels = np.column_stack([u.ravel(), v.ravel()]).astype(float)
    on_face = pixels_on_plane(intrinsics, T_W_C, pixels, PLANE_Z_M)
    on_box = pixels_on_plane(intrinsics, T_W_C, pixels, PLANE_Z_M + 0.03)
    outline = OutlineModel.of(PIECE).posed(part.x_m, part.y_m, part.yaw_rad).astype(np.float32)
    inside = np.array([cv2.pointPolygonTest(outline, (float(x), float(y)), False) >= 0 for x, y in on_face])
    x0, y0, x1, y1 = occluder
    boxed = (on_box[:, 0] > x0) & (on_box[:, 0] < x1) & (on_box[:, 1] > y0) & (on_box[:, 1] < y1)
    camera_z = float(T_W_C.position_m[2])
    rgb = np.full((len(pixels), 3), 110, np.uint8)
    depth = np.full(len(pixels), camera_z, np.float32)
    rgb[inside] = (204, 20, 20)
    depth[inside] = camera_z - PLANE_Z_M
    rgb[boxed] = (25, 25, 25)
    depth[boxed] = camera_z - PLANE_Z_M - 0.03
    shape = (window.height_px, window.width_px)
    return CameraFrame(rgb.reshape(*shape, 3), depth.reshape(shape), intrinsics, T_W_C, 0.0)


def _piece_at() -> PlanarPose:
    # Where the window sees it (about 0.17 m beside the camera's axis).
    T_W_C = camera_pose_world((0.5, 0.0, 0.7), 3.0)
    intrinsics = CameraIntrinsics.from_fov(1920, 1080, 70.0).windowed(PixelWindow(100, 250, 420, 420))
    centre = pixels_on_plane(intrinsics, T_W_C, np.array([[210.0, 210.0]]), PLANE_Z_M)[0]
    return PlanarPose(float(centre[0]), float(centre[1]), 0.4)


def test_a_held_part_half_hidden_by_the_gripper_is_measured_from_its_outline_beside_it() -> None:
    truth = _piece_at()
    # The gripper's body over the part's middle, 3 cm above its top face: its edge against the part is no outline.
    occluder = (truth.x_m - 0.06, truth.y_m - 0.012, truth.x_m + 0.06, truth.y_m + 0.012)
    expected = PlanarPose(truth.x_m + 0.012, truth.y_m - 0.006, truth.yaw_rad + math.radians(3))  # a pick error
    measured = measure_held(
        _frame(truth, occluder), DEFAULT_COLOUR_TABLE["red"], OutlineModel.of(PIECE), PLANE_Z_M, expected
    )
    assert measured.trusted, measured.reason
    assert measured.pose is not None
    assert math.hypot(measured.pose.x_m - truth.x_m, measured.pose.y_m - truth.y_m) < 0.0006
    assert abs(math.degrees(measured.pose.yaw_rad - truth.yaw_rad)) < 0.5


def test_a_held_part_hidden_under_the_gripper_is_not_trusted() -> None:
    truth = _piece_at()
    occluder = (truth.x_m - 0.06, truth.y_m - 0.06, truth.x_m + 0.06, truth.y_m + 0.06)
    measured = measure_held(
        _frame(truth, occluder), DEFAULT_COLOUR_TABLE["red"], OutlineModel.of(PIECE), PLANE_Z_M, truth
    )
    assert not measured.trusted
    assert "outline points" in measured.reason


def test_the_correction_puts_the_part_where_the_plan_expects_it() -> None:
    expected = PlanarPose(0.001, 0.012, 0.0)  # the part in the TCP's frame, as the pick meant it
    measured = PlanarPose(-0.008, 0.015, math.radians(2.0))  # where the camera found it
    correction = compose(expected, inverse(measured))
    plan = PlanarPose(0.52, -0.03, 1.1)  # Place's TCP pose
    where_meant = compose(plan, expected)
    where_put = compose(compose(plan, correction), measured)
    assert math.hypot(where_meant.x_m - where_put.x_m, where_meant.y_m - where_put.y_m) < 1e-12
    assert abs(where_meant.yaw_rad - where_put.yaw_rad) < 1e-12
    assert relative(plan, compose(plan, expected)) == expected or math.isclose(
        relative(plan, compose(plan, expected)).y_m, expected.y_m
    )


def test_place_reads_the_correction_from_the_blackboard(bt_blackboard) -> None:
    context = make_context(gripper_width_m=0.03, object_width_m=0.03)
    bt_blackboard.set("/piece/target", PlanarPose(0.5, 0.0, 0.3))
    correction = PlanarPose(0.004, -0.002, math.radians(1.0))
    bt_blackboard.set("/piece/held_correction", correction)
    release = Release("x", 0.07)
    held = Place("place piece", "piece", PIECE, release=release, held=True)
    held.setup(context=context)
    held.stages(context)
    assert held.corrected_by == correction
    plain = Place("place piece again", "piece", PIECE, release=release)
    plain.setup(context=context)
    plain.stages(context)
    assert plain.corrected_by is None
    bt_blackboard.set("/piece/held_correction", None)  # the set-down's way: nothing measured
    held.stages(context)
    assert held.corrected_by is None


def test_the_look_is_beside_the_camera_on_the_picks_side_the_pads_closing_along_x() -> None:
    x, y, yaw = look_pose((0.5, 0.0), PlanarPose(0.55, -0.16, 0.0), 1.4)
    assert (x, y) == (0.5, -0.3) and math.isclose(yaw, 0.0)
    x, y, yaw = look_pose((0.5, 0.0), PlanarPose(0.45, 0.2, 0.0), 3.0)
    assert (x, y) == (0.5, 0.3) and math.isclose(yaw, math.pi)
    x, y, yaw = look_pose((0.5, 0.0), PlanarPose(0.45, 0.2, 0.0), 3.0, quarter_turn=True)
    assert math.isclose(yaw, math.pi / 2)


def _names(node: py_trees.behaviour.Behaviour) -> list[str]:
    return [n.name for n in node.iterate()]


def test_among_neighbours_an_irregular_part_is_looked_at_in_the_fingers_a_box_is_set_down() -> None:
    release = Release("x", 0.07)
    piece = _transfer(Target("red", 0.5, 0.0, 0.0, name="piece", object_type=PIECE), release=release)
    names = _names(piece)
    assert "look at piece in the fingers, else set it down" in names
    assert "set piece down to look again" in names  # the fallback
    looks = [n for n in piece.iterate() if isinstance(n, LookAtHeld)]
    assert [look.quarter_turn for look in looks] == [False, True]
    (place,) = [n for n in piece.iterate() if isinstance(n, Place) and n.name == "place piece"]
    assert place.held
    cube = _transfer(Target("red", 0.5, 0.0, 0.0, object_type=CUBE), release=release)
    assert not any(isinstance(n, LookAtHeld) for n in cube.iterate())
    assert "set red down to look again" in _names(cube)
    free = _transfer(Target("red", 0.5, 0.0, 0.0, name="piece", object_type=PIECE))
    assert not any(isinstance(n, LookAtHeld) for n in free.iterate())
    assert keys.held_look("piece") == "/piece/held_look"


def test_edges_that_leave_a_direction_unfixed_give_an_infinite_spread_not_a_failure() -> None:
    from bt_arrange.perception.held import fit_sigmas

    along_x = np.column_stack([np.zeros(50), np.ones(50), np.linspace(-0.02, 0.02, 50)])  # one edge, normal y
    assert fit_sigmas(along_x) == (math.inf, math.inf)
    assert fit_sigmas(np.zeros((10, 3))) == (math.inf, math.inf)
    square = np.vstack(
        [
            np.column_stack([np.ones(40), np.zeros(40), np.linspace(-0.02, 0.02, 40)]),
            np.column_stack([np.zeros(40), np.ones(40), np.linspace(0.02, -0.02, 40)]),
        ]
    )
    sigma_m, sigma_rad = fit_sigmas(square)
    assert 0.0 < sigma_m < 0.001 and 0.0 < sigma_rad < 0.1
