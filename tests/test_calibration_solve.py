"""The calibration's solves on synthetic views with known truth: intrinsics, board poses, AX = YB."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from bt_arrange.calibration import BoardView, CharucoBoard, linear_ax_yb, solve_eye_to_hand, solve_intrinsics
from bt_arrange.calibration.board import TABLE_SHEET, TABLE_SHEET_THICKNESS_M, BoardObservation
from bt_arrange.calibration.procedure import WORKING_TCP_HEIGHTS_M, BoardMount, board_poses, working_plane_poses
from bt_arrange.calibration.solve import check_view_count, solve_on_table_plane
from bt_arrange.errors import PlanError
from bt_arrange.geometry import Pose
from bt_arrange.plan.camera_view import CameraView
from bt_arrange.robot import CameraIntrinsics

TRUE_K = CameraIntrinsics(1920, 1080, 1385.0, 1383.0, 966.0, 533.0, (-0.12, 0.06, 8e-4, -5e-4, 0.0))
NOMINAL_K = CameraIntrinsics.from_fov(1920, 1080, 70.0)
NOMINAL_CAMERA = Pose.from_rotation([0.5, 0.0, 0.7], [[0.0, -1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])


def _small_turn(rx: float, ry: float, rz: float) -> np.ndarray:
    rotation, _ = cv2.Rodrigues(np.array([rx, ry, rz]))
    return np.asarray(rotation)


TRUE_CAMERA = Pose.from_rotation([0.512, -0.009, 0.715], NOMINAL_CAMERA.rotation @ _small_turn(0.01, -0.015, 0.02))
_MOUNT_ERROR = Pose.from_rotation([0.002, -0.003, 0.001], _small_turn(0.01, 0.005, -0.02))
TRUE_MOUNT = BoardMount().board_to_tool(CharucoBoard()) @ _MOUNT_ERROR


def _views(noise_px: float = 0.0, seed: int = 0) -> list[BoardView]:
    """The procedure's poses, each board's corners projected through the true camera and lens."""
    board = CharucoBoard()
    rng = np.random.default_rng(seed)
    views = []
    for tcp in board_poses(CameraView(NOMINAL_K, NOMINAL_CAMERA), board, count=20):
        T_C_P = TRUE_CAMERA.inverse() @ tcp @ TRUE_MOUNT
        points = board.corners_m()
        pixels, _ = cv2.projectPoints(points, cv2.Rodrigues(T_C_P.rotation)[0], T_C_P.position_m, TRUE_K.matrix,
                                      np.asarray(TRUE_K.distortion))  # fmt: skip
        pixels = pixels.reshape(-1, 2) + rng.normal(0.0, noise_px, (len(points), 2))
        inside = (pixels[:, 0] > 0) & (pixels[:, 0] < 1919) & (pixels[:, 1] > 0) & (pixels[:, 1] < 1079)
        ids = np.flatnonzero(inside).astype(np.int32)
        views.append(BoardView(BoardObservation(pixels[inside], ids, points[inside]), tcp))
    return views


def _rotation_error_mrad(a: Pose, b: Pose) -> float:
    relative = a.rotation.T @ b.rotation
    return math.acos(max(-1.0, min(1.0, (np.trace(relative) - 1) / 2))) * 1000


def test_intrinsics_and_distortion_are_recovered_from_exact_corners() -> None:
    solution = solve_intrinsics([v.observation for v in _views()], 1920, 1080)
    k = solution.intrinsics
    assert solution.reprojection_error_px < 1e-3
    assert np.allclose([k.fx_px, k.fy_px, k.cx_px, k.cy_px], [1385.0, 1383.0, 966.0, 533.0], atol=0.05)
    assert np.allclose(k.distortion, TRUE_K.distortion, atol=1e-4)


def test_the_linear_ax_yb_solve_is_exact_on_exact_poses() -> None:
    rng = np.random.default_rng(3)
    a = [Pose.from_rotation(rng.normal(0, 0.3, 3), _small_turn(*rng.normal(0, 0.8, 3))) for _ in range(6)]
    b = [TRUE_CAMERA.inverse() @ ai @ TRUE_MOUNT for ai in a]
    x, y = linear_ax_yb(a, b)
    assert np.allclose(x.matrix, TRUE_MOUNT.matrix, atol=1e-9)
    assert np.allclose(y.matrix, TRUE_CAMERA.matrix, atol=1e-9)


def test_camera_to_base_is_recovered_within_half_a_millimetre_from_noisy_corners() -> None:
    views = _views(noise_px=0.15, seed=1)
    intrinsics = solve_intrinsics([v.observation for v in views], 1920, 1080).intrinsics
    solution = solve_eye_to_hand(views, intrinsics)
    error_mm = np.linalg.norm(solution.camera_to_base.position_m - TRUE_CAMERA.position_m) * 1000
    assert error_mm < 0.5, error_mm
    assert _rotation_error_mrad(solution.camera_to_base, TRUE_CAMERA) < 1.5
    assert solution.reprojection_error_px < 0.3
    assert np.linalg.norm(solution.board_to_tool.position_m - TRUE_MOUNT.position_m) * 1000 < 1.0


def test_too_few_views_is_one_line_with_the_counts() -> None:
    with pytest.raises(PlanError, match=r"too few views to calibrate: 3 usable of 10 poses \(7 skipped"):
        check_view_count(3, skipped=7)


def test_the_board_is_found_in_its_own_image_with_every_corner() -> None:
    board = CharucoBoard()
    image = board.plate_image(3000.0)
    observation = board.detect(np.dstack([image] * 3))
    assert observation is not None and observation.count == board.corner_count
    # Corner k of the pattern lies where the board frame says, at 3 px per mm (pixel-centre convention).
    expected = (board.corners_m()[observation.ids, :2] + board.margin_m) * 3000.0 - 0.5
    assert np.abs(observation.image_points_px - expected).max() < 0.1


def test_with_exact_arm_poses_freeing_the_intrinsics_in_the_last_refinement_recovers_the_camera_closely() -> None:
    views = _views(noise_px=0.15, seed=1)
    intrinsics = solve_intrinsics([v.observation for v in views], 1920, 1080).intrinsics
    solution = solve_eye_to_hand(views, intrinsics, refine_intrinsics=True)
    assert np.linalg.norm(solution.camera_to_base.position_m - TRUE_CAMERA.position_m) * 1000 < 0.1
    assert _rotation_error_mrad(solution.camera_to_base, TRUE_CAMERA) < 0.3


# -- camera to base referenced to the table plane --------------------------------------------------

SHEET_ON_TABLE = Pose.from_rotation(
    [0.27, -0.22, TABLE_SHEET_THICKNESS_M],
    np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]) @ _small_turn(0.0, 0.0, 0.05) @ np.diag([1, -1, -1]),
)


def _observe(board: CharucoBoard, T_C_P: Pose, rng: np.random.Generator, noise_px: float) -> BoardObservation:
    points = board.corners_m()
    pixels, _ = cv2.projectPoints(points, cv2.Rodrigues(T_C_P.rotation)[0], T_C_P.position_m, TRUE_K.matrix,
                                  np.asarray(TRUE_K.distortion))  # fmt: skip
    pixels = pixels.reshape(-1, 2) + rng.normal(0.0, noise_px, (len(points), 2))
    inside = (pixels[:, 0] > 0) & (pixels[:, 0] < 1919) & (pixels[:, 1] > 0) & (pixels[:, 1] < 1079)
    return BoardObservation(pixels[inside], np.flatnonzero(inside).astype(np.int32), points[inside])


def _arm_error(tcp: Pose) -> Pose:
    """An arm right where it works (TCP 4 to 10 cm above the table) and off above it: what the controller reports.

    1 mm along x and 0.5 mm along z per 10 cm of height above 7 cm: the kind of error a real arm's
    link lengths give, larger the further its configuration is from where it was levelled.
    """
    rise = tcp.position_m[2] - 0.07
    return Pose.from_rotation(tcp.position_m + np.array([0.010, 0.0, 0.005]) * rise, tcp.rotation)


def _procedure_views(noise_px: float, seed: int, arm_error: bool) -> tuple[list[BoardView], BoardObservation]:
    """The procedure's lens and working-plane views of the true camera, and the table sheet's view."""
    board, view = CharucoBoard(), CameraView(NOMINAL_K, NOMINAL_CAMERA)
    rng = np.random.default_rng(seed)
    views = []
    lens, working_plane = board_poses(view, board, count=14), working_plane_poses(view, board, count=14)
    for tcps, working in ((lens, False), (working_plane, True)):
        for tcp in tcps:
            observation = _observe(board, TRUE_CAMERA.inverse() @ tcp @ TRUE_MOUNT, rng, noise_px)
            views.append(BoardView(observation, _arm_error(tcp) if arm_error else tcp, working))
    return views, _observe(TABLE_SHEET, TRUE_CAMERA.inverse() @ SHEET_ON_TABLE, rng, noise_px)


def _table_error_mm(intrinsics: CameraIntrinsics, camera: Pose) -> float:
    """Mean planar error (mm) of points on a cube's top (5 cm) over the working area, seen by the true camera."""
    points = np.array([[x, y, 0.05] for x in np.linspace(0.32, 0.64, 5) for y in np.linspace(-0.26, 0.26, 5)])
    in_camera = TRUE_CAMERA.inverse()
    pixels, _ = cv2.projectPoints(points, cv2.Rodrigues(in_camera.rotation)[0], in_camera.position_m,
                                  TRUE_K.matrix, np.asarray(TRUE_K.distortion))  # fmt: skip
    rays = cv2.undistortPoints(pixels, intrinsics.matrix, np.asarray(intrinsics.distortion)).reshape(-1, 2)
    directions = np.c_[rays, np.ones(len(rays))] @ camera.rotation.T
    hits = camera.position_m + directions * ((0.05 - camera.position_m[2]) / directions[:, 2])[:, None]
    return float(np.linalg.norm((hits - points)[:, :2], axis=1).mean() * 1000)


def test_the_table_plane_solve_recovers_the_camera_from_noisy_corners() -> None:
    views, sheet = _procedure_views(noise_px=0.1, seed=2, arm_error=False)
    working = [v for v in views if v.working_plane]
    # The solve itself, on the true lens: the camera to well under 0.5 mm and 1 mrad.
    solution = solve_on_table_plane(working, TRUE_K, sheet, solve_eye_to_hand(views, TRUE_K), TABLE_SHEET_THICKNESS_M)
    error_mm = np.linalg.norm(solution.camera_to_base.position_m - TRUE_CAMERA.position_m) * 1000
    assert error_mm < 0.2, error_mm
    assert _rotation_error_mrad(solution.camera_to_base, TRUE_CAMERA) < 0.4
    assert solution.reprojection_error_px < 0.3
    # On the lens calibrateCamera finds, the pose trades a little with the principal point, but what
    # the camera reports on the table stays right.
    intrinsics = solve_intrinsics([v.observation for v in views] + [sheet], 1920, 1080).intrinsics
    solution = solve_on_table_plane(working, intrinsics, sheet, solve_eye_to_hand(views, intrinsics),
                                    TABLE_SHEET_THICKNESS_M)  # fmt: skip
    assert _table_error_mm(intrinsics, solution.camera_to_base) < 0.05


def test_the_table_plane_keeps_an_arm_wrong_above_where_it_works_out_of_the_camera() -> None:
    views, sheet = _procedure_views(noise_px=0.1, seed=3, arm_error=True)
    intrinsics = solve_intrinsics([v.observation for v in views] + [sheet], 1920, 1080).intrinsics
    every_view = solve_eye_to_hand(views, intrinsics)
    on_plane = solve_on_table_plane([v for v in views if v.working_plane], intrinsics, sheet, every_view,
                                    TABLE_SHEET_THICKNESS_M)  # fmt: skip
    # The plain solve spreads the arm's error at the lens views over the camera; the table plane does not.
    assert _table_error_mm(intrinsics, every_view.camera_to_base) > 0.3
    assert _table_error_mm(intrinsics, on_plane.camera_to_base) < 0.1


def test_the_working_plane_poses_keep_the_gripper_down_over_the_working_area_and_the_board_in_view() -> None:
    view = CameraView(NOMINAL_K, NOMINAL_CAMERA)
    poses = working_plane_poses(view, count=16)
    assert len(poses) == 16
    for tcp in poses:
        assert np.allclose(tcp.rotation[:, 2], [0.0, 0.0, -1.0]), "the gripper points straight down"
        assert 0.30 <= tcp.position_m[0] <= 0.66 and -0.28 <= tcp.position_m[1] <= 0.28
        assert tcp.position_m[2] in WORKING_TCP_HEIGHTS_M
    yaws = {round(math.degrees(p.yaw_rad)) for p in poses}
    assert len(yaws) > 8, "the board turns about the vertical from pose to pose"


def test_the_two_boards_are_never_taken_for_each_other() -> None:
    flange, sheet = CharucoBoard(), TABLE_SHEET
    for board, other in ((flange, sheet), (sheet, flange)):
        image = np.dstack([other.plate_image(3000.0)] * 3)
        assert board.detect(image) is None
        assert other.detect(image) is not None
