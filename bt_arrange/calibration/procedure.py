"""The calibration procedure: where the board goes, and the tree that takes it there and looks.

The board is bolted to the flange beside the gripper (``BoardMount``): its face looks the way the
gripper's back does (up, when the gripper points down), its centre ``offset_m`` from the TCP
across the closing axis, so neither the fingers nor the wrist cover it from above. The mount is
what a drawing of the bracket says; the solve finds the true one (``HandEyeSolution.board_to_tool``),
so it needs to be right only to plan the poses.

``board_poses`` spreads the board over the camera's view at two heights and tilts it by
``tilt_deg`` about alternating axes (the tilts make the focal length observable); each pose's
TCP pose follows from the mount. ``calibration_tree`` is one ``view i`` sequence per pose (move,
capture) under a ``FailureIsSuccess``, so an unreachable pose or a board not seen is skipped,
then the arm parks and ``SolveCalibration`` solves (or fails with one line: too few views).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import py_trees
from numpy.typing import ArrayLike

from bt_arrange.behaviours.looking import MoveHome
from bt_arrange.calibration.behaviours import CaptureBoard, CaptureSheet, MoveBoard, SolveCalibration
from bt_arrange.calibration.board import CharucoBoard
from bt_arrange.geometry import FloatArray, Pose
from bt_arrange.motion import gripper_down_rotation
from bt_arrange.plan.camera_view import CameraView

#: The heights above the table (m) the board's centre is taken to: 40 and 30 cm below the camera.
BOARD_HEIGHTS_M = (0.30, 0.40)
#: Where in the image (fractions of width and height) the board's centre is put at each height.
IMAGE_SPOTS = ((0.5, 0.5), (0.22, 0.3), (0.78, 0.3), (0.22, 0.7), (0.78, 0.7), (0.5, 0.25), (0.5, 0.75))
#: Where the arm works (base frame, m): the trials' targets and the parts' scatter area. The working-plane
#: views put the TCP over it, gripper down, as it is when it grasps, places and pushes.
WORKING_AREA_X_M = (0.30, 0.66)
WORKING_AREA_Y_M = (-0.28, 0.28)
#: The TCP's heights above the table in the working-plane views: the grasp's and the approach's,
#: about (2.5 and 10 cm for a 5 cm cube), kept 4 cm clear of the table.
WORKING_TCP_HEIGHTS_M = (0.04, 0.10)
#: How far above its working-plane pose the board is first brought (a joint motion near the table
#: could dip the fingers into it; from straight above, it cannot).
APPROACH_HEIGHT_M = 0.15


@dataclass(frozen=True)
class BoardMount:
    """Where the board sits on the tool: ``T_T_P`` (board frame in the TCP frame), nominally.

    The pattern's centre lies ``offset_m`` along the TCP's y axis (across the closing axis) and
    ``height_m`` along its z axis (negative: towards the flange); the board's axes are the TCP's,
    so its face looks along -z of the TCP (up when the gripper points down).
    """

    offset_m: float = 0.17
    height_m: float = -0.06

    def board_to_tool(self, board: CharucoBoard) -> Pose:
        """``T_T_P`` of this mount for ``board`` (the board frame's origin is a pattern corner)."""
        centre = np.array([0.0, self.offset_m, self.height_m])
        return Pose.from_rotation(centre - board.centre_m, np.eye(3))


def _rotation_about(axis_xyz: ArrayLike, angle_rad: float) -> FloatArray:
    axis = np.asarray(axis_xyz, dtype=float)
    axis = axis / np.linalg.norm(axis)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + math.sin(angle_rad) * k + (1 - math.cos(angle_rad)) * (k @ k)


def board_poses(
    view: CameraView,
    board: CharucoBoard | None = None,
    mount: BoardMount | None = None,
    count: int = 20,
    tilt_deg: float = 25.0,
    table_z_m: float = 0.0,
) -> list[Pose]:
    """``count`` TCP poses that put the board over the camera's view, tilted; spread first, then filled in.

    The board's y axis points away from the robot's base (so the arm stays behind it as the camera
    sees it); its face is turned ``tilt_deg`` about the board's x or y axis, the sign alternating.
    """
    board = board or CharucoBoard()
    mount = mount or BoardMount()
    T_T_P = mount.board_to_tool(board)
    intrinsics, T_W_C = view.intrinsics, view.camera_pose_world
    tilts = ((1, 0), (0, 1), (-1, 0), (0, -1), (1, 1), (-1, -1), (1, -1), (-1, 1))
    poses: list[Pose] = []
    candidates = []
    for height_index, height_m in enumerate(BOARD_HEIGHTS_M):
        for spot_index, (fu, fv) in enumerate(IMAGE_SPOTS):
            candidates.append((height_index, spot_index, height_m, fu, fv))
    # Interleave the heights so that a short procedure still sees two distances.
    candidates.sort(key=lambda c: (c[1], c[0]))
    for k in range(count):
        height_index, spot_index, height_m, fu, fv = candidates[k % len(candidates)]
        pixel = np.array([fu * (intrinsics.width_px - 1), fv * (intrinsics.height_px - 1), 1.0])
        ray = T_W_C.rotation @ np.linalg.solve(intrinsics.matrix, pixel)
        z = table_z_m + height_m
        centre = T_W_C.position_m + ray * (z - T_W_C.position_m[2]) / ray[2]
        away = np.array([centre[0], centre[1], 0.0])
        y_axis = away / np.linalg.norm(away)
        z_axis = np.array([0.0, 0.0, -1.0])  # into the board: its face looks up
        x_axis = np.cross(y_axis, z_axis)
        level = np.column_stack([x_axis, y_axis, z_axis])
        round_index = k // len(candidates)
        tx, ty = tilts[(k + 3 * round_index) % len(tilts)]
        tilt = math.radians(tilt_deg)
        rotation = level @ _rotation_about([tx, ty, 0.0], tilt) if (tx or ty) else level
        # Yaw the board a little about its normal too, different from pose to pose.
        rotation = rotation @ _rotation_about([0.0, 0.0, 1.0], math.radians(10.0 * ((k % 5) - 2)))
        T_W_P = Pose.from_rotation(centre - rotation @ board.centre_m, rotation)
        poses.append(T_W_P @ T_T_P.inverse())
    return poses


def _inside_image(view: CameraView, T_W_P: Pose, board: CharucoBoard, margin_px: float = 30.0) -> bool:
    """Whether every corner of the plate falls inside the nominal camera's image, ``margin_px`` in."""
    width, height = board.plate_size_m
    m = board.margin_m
    corners = np.array([[-m, -m, 0.0], [width - m, -m, 0.0], [width - m, height - m, 0.0], [-m, height - m, 0.0]])
    T_C_P = view.camera_pose_world.inverse() @ T_W_P
    points = corners @ T_C_P.rotation.T + T_C_P.position_m
    k = view.intrinsics
    u = k.fx_px * points[:, 0] / points[:, 2] + k.cx_px
    v = k.fy_px * points[:, 1] / points[:, 2] + k.cy_px
    return bool(
        np.all(points[:, 2] > 0)
        and np.all((u > margin_px) & (u < k.width_px - margin_px) & (v > margin_px) & (v < k.height_px - margin_px))
    )


def working_plane_poses(
    view: CameraView,
    board: CharucoBoard | None = None,
    mount: BoardMount | None = None,
    count: int = 10,
    table_z_m: float = 0.0,
) -> list[Pose]:
    """``count`` TCP poses where the arm works: gripper down over the working area, at the working heights.

    The TCP goes to a grid of the working area (``WORKING_AREA_*``) at ``WORKING_TCP_HEIGHTS_M``, the
    gripper pointing straight down as when it grasps and pushes, turned so that the board (beside
    the TCP on its mount) lies in the nominal camera's image; the side it lies on turns from pose
    to pose (beside, ahead, the other side, behind, as the image allows), so the turns about the
    vertical tell the board's mount apart from the camera's place. The poses are taken spread over
    the grid first. The arm's kinematic error at these poses is the error it has where it works,
    so a camera placed by them agrees with the arm there (docs/calibration.md).
    """
    board = board or CharucoBoard()
    mount = mount or BoardMount()
    T_T_P = mount.board_to_tool(board)
    columns, rows = 4, 5
    grid = [
        (float(x), float(y), table_z_m + z)
        for z in WORKING_TCP_HEIGHTS_M
        for x in np.linspace(*WORKING_AREA_X_M, columns)
        for y in np.linspace(*WORKING_AREA_Y_M, rows)
    ]
    # A stride coprime with the grid's size visits it spread out (neighbours far apart in the order).
    stride = next(s for s in (7, 11, 13, 3) if math.gcd(s, len(grid)) == 1)
    poses: list[Pose] = []
    for k in range(len(grid)):
        if len(poses) == count:
            break
        x, y, z = grid[(k * stride) % len(grid)]
        radial = math.atan2(y, x)
        for turn in range(4):
            # The board lies along the TCP's y axis, which a gripper-down yaw of a points along a - 90 deg.
            board_direction = radial + math.pi / 2 * ((k + turn) % 4 - 1)
            rotation = gripper_down_rotation(board_direction + math.pi / 2)
            tcp = Pose.from_rotation([x, y, z], rotation)
            if _inside_image(view, tcp @ T_T_P, board):
                poses.append(tcp)
                break
    return poses


def calibration_tree(
    poses: list[Pose],
    board: CharucoBoard | None = None,
    cell: str = "",
    plane_poses: Sequence[Pose] = (),
    sheet: CharucoBoard | None = None,
) -> py_trees.behaviour.Behaviour:
    """The procedure as a tree: the table sheet, per pose move and capture (skipped on failure), park, solve.

    ``poses`` are the lens views (``board_poses``); ``plane_poses`` the working-plane views
    (``working_plane_poses``), each approached from ``APPROACH_HEIGHT_M`` straight above; ``sheet``
    the board lying on the table, captured first (without it, the solve has no table plane).
    """
    board = board or CharucoBoard()
    children: list[py_trees.behaviour.Behaviour] = []
    if sheet is not None:
        children.append(
            py_trees.decorators.FailureIsSuccess(
                "go on if the sheet is not seen", CaptureSheet("capture the table sheet", sheet)
            )
        )
    views: list[py_trees.behaviour.Behaviour] = []
    for index, pose in enumerate(poses):
        sequence = py_trees.composites.Sequence(
            f"view {index}",
            memory=True,
            children=[MoveBoard(f"move the board to pose {index}", pose), CaptureBoard(f"capture {index}", board)],
        )
        views.append(py_trees.decorators.FailureIsSuccess(f"skip view {index} if it fails", sequence))
    for index, pose in enumerate(plane_poses, start=len(poses)):
        above = Pose.from_rotation(pose.position_m + np.array([0.0, 0.0, APPROACH_HEIGHT_M]), pose.rotation)
        sequence = py_trees.composites.Sequence(
            f"view {index} (working plane)",
            memory=True,
            children=[
                MoveBoard(f"bring the board above pose {index}", above),
                MoveBoard(f"lower the board to pose {index}", pose),
                CaptureBoard(f"capture {index}", board, working_plane=True),
                MoveBoard(f"raise the board from pose {index}", above),
            ],
        )
        views.append(py_trees.decorators.FailureIsSuccess(f"skip view {index} if it fails", sequence))
    children += [
        py_trees.composites.Sequence("views", memory=True, children=views),
        MoveHome("park the arm"),
        SolveCalibration("solve", len(poses) + len(plane_poses), cell=cell, board=board),
    ]
    return py_trees.composites.Sequence("calibrate", memory=True, children=children)
