"""The calibration's solves on synthetic views with known truth: intrinsics, board poses, AX = YB."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from bt_arrange.calibration import BoardView, CharucoBoard, linear_ax_yb, solve_eye_to_hand, solve_intrinsics
from bt_arrange.calibration.board import BoardObservation
from bt_arrange.calibration.procedure import BoardMount, board_poses
from bt_arrange.calibration.solve import check_view_count
from bt_arrange.errors import PlanError
from bt_arrange.geometry import Pose
from bt_arrange.plancheck import CameraView
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
