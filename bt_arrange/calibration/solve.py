"""Solving a calibration from board views: intrinsics and distortion, then camera to base (eye-to-hand).

1. **Intrinsics** (``solve_intrinsics``): ``cv2.calibrateCamera`` on the ChArUco corners of every
   view (Zhang's method, then Levenberg-Marquardt over the pinhole, the distortion and one board
   pose per view). ``k3`` is held at 0 (``CALIB_FIX_K3``), as OpenCV advises for lenses that are not
   wide-angle: k1, k2, p1 and p2 describe a 6-8 mm lens, and a free k3 trades off against k1 and k2
   in few views.
2. **Camera to base** (``solve_eye_to_hand``): the board is fixed to the flange and the camera to the
   cell, so for every view ``i`` the arm's TCP pose ``A_i = T_B_T`` (from the controller) and the
   camera's board pose ``B_i = T_C_P`` (from the image) satisfy ``A_i X = Y B_i`` with the two
   unknown constant transforms ``X = T_T_P`` (board on the tool) and ``Y = T_B_C`` (camera in the base).
   A linear least squares on the rotations (the null space of the stacked
   ``R_Ai R_X - R_Y R_Bi = 0``, Shah 2013) and then on the translations gives a start; a
   Levenberg-Marquardt refinement of X and Y on the reprojection error of every corner through
   ``inv(Y) A_i X`` (intrinsics held) finishes it. OpenCV 5's Python build has no
   ``calibrateRobotWorldHandEye``, so this module solves AX = YB itself, with numpy only; it works the
   same on OpenCV 4.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import ArrayLike

from bt_arrange.calibration.board import BoardObservation
from bt_arrange.errors import PlanError
from bt_arrange.geometry import FloatArray, Pose
from bt_arrange.robot import CameraIntrinsics

#: The fewest views a calibration accepts: fewer leave the distortion and the hand-eye solve weak.
MIN_VIEWS = 6


@dataclass(frozen=True)
class BoardView:
    """One view of the procedure: what the camera saw and where the arm's controller says the TCP was."""

    observation: BoardObservation
    #: ``T_B_T``: the TCP in the base frame, from the arm's own kinematics and its joint readings.
    tcp_pose: Pose
    #: Taken where the arm works (``procedure.working_plane_poses``): these place the camera on the table plane.
    working_plane: bool = False


@dataclass(frozen=True)
class IntrinsicsSolution:
    """``solve_intrinsics``'s answer: the intrinsics, the RMS reprojection error, each view's board pose."""

    intrinsics: CameraIntrinsics
    reprojection_error_px: float
    #: ``T_C_P`` of each view, in the order given.
    board_poses: tuple[Pose, ...]


@dataclass(frozen=True)
class HandEyeSolution:
    """``solve_eye_to_hand``'s answer."""

    #: ``T_B_C``, the camera in the base frame.
    camera_to_base: Pose
    #: ``T_T_P``, the board on the tool.
    board_to_tool: Pose
    #: RMS reprojection error (px) of every corner through the arm's poses: ``inv(Y) A_i X``.
    reprojection_error_px: float
    #: RMS distance (mm) between each view's board corners as the arm puts them and as the camera does.
    residual_mm: float
    #: The intrinsics the solve ended with (those given, unless ``refine_intrinsics``).
    intrinsics: CameraIntrinsics | None = None


def _pose(rvec: ArrayLike, tvec: ArrayLike) -> Pose:
    rotation, _ = cv2.Rodrigues(np.asarray(rvec, dtype=np.float64).reshape(3, 1))
    return Pose.from_rotation(np.asarray(tvec, dtype=np.float64).reshape(3), rotation)


def _rvec(rotation: FloatArray) -> FloatArray:
    vector, _ = cv2.Rodrigues(np.asarray(rotation, dtype=np.float64))
    return np.asarray(vector, dtype=np.float64).reshape(3)


def check_view_count(count: int, minimum: int = MIN_VIEWS, skipped: int = 0) -> None:
    """A ``PlanError`` when fewer than ``minimum`` views are usable (one clear line)."""
    if count < minimum:
        raise PlanError(
            f"too few views to calibrate: {count} usable of {count + skipped} poses "
            f"({skipped} skipped: unreachable or the board not seen); at least {minimum} are needed",
            field="views",
            value=count,
            limit=minimum,
        )


def solve_intrinsics(
    observations: Sequence[BoardObservation], width_px: int, height_px: int, initial: CameraIntrinsics | None = None
) -> IntrinsicsSolution:
    """The pinhole and distortion from the board corners of every view (``cv2.calibrateCamera``)."""
    check_view_count(len(observations))
    object_points = [o.board_points_m.astype(np.float32).reshape(-1, 1, 3) for o in observations]
    image_points = [o.image_points_px.astype(np.float32).reshape(-1, 1, 2) for o in observations]
    flags = cv2.CALIB_FIX_K3
    camera_matrix = None
    if initial is not None:
        camera_matrix = initial.matrix.copy()
        flags |= cv2.CALIB_USE_INTRINSIC_GUESS
    criteria = (cv2.TERM_CRITERIA_COUNT + cv2.TERM_CRITERIA_EPS, 200, 1e-12)
    rms, matrix, distortion, rvecs, tvecs = cv2.calibrateCamera(
        object_points, image_points, (width_px, height_px), camera_matrix, None, flags=flags, criteria=criteria
    )
    coefficients = tuple(float(v) for v in np.asarray(distortion).reshape(-1)[:5])
    intrinsics = CameraIntrinsics(
        width_px, height_px, float(matrix[0, 0]), float(matrix[1, 1]), float(matrix[0, 2]), float(matrix[1, 2]),
        coefficients,
    )  # fmt: skip
    poses = tuple(_pose(r, t) for r, t in zip(rvecs, tvecs, strict=True))
    return IntrinsicsSolution(intrinsics, float(rms), poses)


def _nearest_rotation(m: FloatArray) -> FloatArray:
    u, _, vt = np.linalg.svd(m)
    r = u @ vt
    if np.linalg.det(r) < 0:
        u[:, -1] *= -1
        r = u @ vt
    return np.asarray(r)


def linear_ax_yb(a: Sequence[Pose], b: Sequence[Pose]) -> tuple[Pose, Pose]:
    """X and Y with ``A_i X = Y B_i`` by linear least squares (rotations, then translations)."""
    if len(a) != len(b) or len(a) < 3:
        raise PlanError(f"AX = YB needs at least 3 pose pairs, got {min(len(a), len(b))}")
    rows = []
    for ai, bi in zip(a, b, strict=True):
        # R_A R_X - R_Y R_B = 0, with vec() column-major: vec(R_A R_X) = (I kron R_A) vec(R_X),
        # vec(R_Y R_B) = (R_B^T kron I) vec(R_Y).
        rows.append(np.hstack([np.kron(np.eye(3), ai.rotation), -np.kron(bi.rotation.T, np.eye(3))]))
    _, _, vt = np.linalg.svd(np.vstack(rows))
    solution = vt[-1]
    rx = solution[:9].reshape(3, 3, order="F")
    ry = solution[9:].reshape(3, 3, order="F")
    scale = np.cbrt(np.linalg.det(rx))
    rx, ry = _nearest_rotation(rx / scale), _nearest_rotation(ry / scale)
    # R_A t_X + t_A = R_Y t_B + t_Y  ->  [R_A, -I] [t_X; t_Y] = R_Y t_B - t_A
    lhs = np.vstack([np.hstack([ai.rotation, -np.eye(3)]) for ai in a])
    rhs = np.concatenate([ry @ bi.position_m - ai.position_m for ai, bi in zip(a, b, strict=True)])
    t, *_ = np.linalg.lstsq(lhs, rhs, rcond=None)
    return Pose.from_rotation(t[:3], rx), Pose.from_rotation(t[3:], ry)


def _project(intrinsics: CameraIntrinsics, T_C_P: Pose, points_m: FloatArray) -> FloatArray:
    pixels, _ = cv2.projectPoints(
        np.asarray(points_m, dtype=np.float64).reshape(-1, 1, 3),
        _rvec(T_C_P.rotation),
        T_C_P.position_m.reshape(3, 1),
        intrinsics.matrix,
        np.asarray(intrinsics.distortion, dtype=np.float64),
    )
    return np.asarray(pixels, dtype=np.float64).reshape(-1, 2)


def _unpack(p: FloatArray) -> tuple[Pose, Pose]:
    return _pose(p[0:3], p[3:6]), _pose(p[6:9], p[9:12])


def _with_intrinsics(p: FloatArray, intrinsics: CameraIntrinsics) -> CameraIntrinsics:
    """``intrinsics`` with fx, fy, cx, cy, k1, k2, p1, p2 from ``p[12:20]`` when the parameters hold them."""
    if len(p) == 12:
        return intrinsics
    fx, fy, cx, cy, k1, k2, p1, p2 = (float(v) for v in p[12:20])
    return CameraIntrinsics(intrinsics.width_px, intrinsics.height_px, fx, fy, cx, cy, (k1, k2, p1, p2, 0.0))


def _residuals(p: FloatArray, views: Sequence[BoardView], intrinsics: CameraIntrinsics) -> FloatArray:
    intrinsics = _with_intrinsics(p, intrinsics)
    x, y = _unpack(p)
    y_inv = y.inverse()
    out = []
    for view in views:
        predicted = _project(intrinsics, y_inv @ view.tcp_pose @ x, view.observation.board_points_m)
        out.append((predicted - view.observation.image_points_px).reshape(-1))
    return np.concatenate(out)


def _levenberg_marquardt(
    residuals: Callable[[FloatArray], FloatArray], p: FloatArray, steps: FloatArray, iterations: int = 50
) -> FloatArray:
    """Minimise ``residuals(p)`` (numerical Jacobian with ``steps``, Marquardt damping)."""
    residual = residuals(p)
    cost = float(residual @ residual)
    damping = 1e-3
    for _ in range(iterations):
        jacobian = np.empty((len(residual), len(p)))
        for k in range(len(p)):
            shifted = p.copy()
            shifted[k] += steps[k]
            jacobian[:, k] = (residuals(shifted) - residual) / steps[k]
        normal = jacobian.T @ jacobian
        gradient = jacobian.T @ residual
        improved = False
        for _ in range(10):
            # The pseudo-inverse: a direction the views leave free stays where the start put it.
            delta = -np.linalg.lstsq(normal + damping * np.diag(np.diag(normal)), gradient, rcond=1e-12)[0]
            candidate = p + delta
            candidate_residual = residuals(candidate)
            candidate_cost = float(candidate_residual @ candidate_residual)
            if candidate_cost < cost:
                p, residual, improved = candidate, candidate_residual, True
                relative = (cost - candidate_cost) / max(cost, 1e-30)
                cost = candidate_cost
                damping = max(damping / 10, 1e-12)
                break
            damping *= 10
        if not improved or relative < 1e-12:
            break
    return p


def board_pose(observation: BoardObservation, intrinsics: CameraIntrinsics) -> Pose:
    """``T_C_P``, the board in the camera frame, from its corners (``solvePnP`` IPPE, then ``solvePnPRefineLM``)."""
    matrix, distortion = intrinsics.matrix, np.asarray(intrinsics.distortion, dtype=np.float64)
    points = observation.board_points_m.reshape(-1, 1, 3)
    pixels = observation.image_points_px.reshape(-1, 1, 2)
    ok, rvec, tvec = cv2.solvePnP(points, pixels, matrix, distortion, flags=cv2.SOLVEPNP_IPPE)
    if not ok:
        raise PlanError("a board view gives no pose (solvePnP failed)")
    rvec, tvec = cv2.solvePnPRefineLM(points, pixels, matrix, distortion, rvec, tvec)
    return _pose(rvec, tvec)


def _hand_eye_figures(
    views: Sequence[BoardView], intrinsics: CameraIntrinsics, x: Pose, y: Pose
) -> tuple[float, float]:
    """RMS reprojection error (px) through the arm's poses, and the RMS corner distance (mm) arm against camera."""
    residual = _residuals(np.concatenate([_rvec(x.rotation), x.position_m, _rvec(y.rotation), y.position_m]),
                          views, intrinsics)  # fmt: skip
    rms_px = float(math.sqrt(np.mean(residual.reshape(-1, 2) ** 2) * 2))
    distances = []
    for view in views:
        by_arm = (view.tcp_pose @ x).matrix
        by_camera = (y @ board_pose(view.observation, intrinsics)).matrix
        points = np.c_[view.observation.board_points_m, np.ones(view.observation.count)].T
        distances.append(np.linalg.norm((by_arm @ points - by_camera @ points)[:3], axis=0))
    return rms_px, float(math.sqrt(np.mean(np.concatenate(distances) ** 2)) * 1000)


def solve_eye_to_hand(
    views: Sequence[BoardView], intrinsics: CameraIntrinsics, refine_intrinsics: bool = False
) -> HandEyeSolution:
    """Camera to base (and board to tool) from the views, with ``intrinsics`` held.

    Each view's board pose comes from its corners (``solvePnP`` with the intrinsics); the linear
    AX = YB solve starts the refinement on the reprojection error of every corner.
    ``refine_intrinsics`` also frees the pinhole and the distortion in the last refinement (the board
    poses then follow the arm's: fewer unknowns, but the arm's kinematic error enters the intrinsics).
    """
    check_view_count(len(views))
    board_poses = [board_pose(view.observation, intrinsics) for view in views]
    x0, y0 = linear_ax_yb([v.tcp_pose for v in views], board_poses)
    start = np.concatenate([_rvec(x0.rotation), x0.position_m, _rvec(y0.rotation), y0.position_m])
    if refine_intrinsics:
        k = intrinsics
        start = np.concatenate([start, [k.fx_px, k.fy_px, k.cx_px, k.cy_px, *k.distortion[:4]]])
    steps = np.array([1e-7] * 12 + [1e-4] * 4 + [1e-7] * 4)[: len(start)]
    solved = _levenberg_marquardt(lambda p: _residuals(p, views, intrinsics), start, steps)
    intrinsics = _with_intrinsics(solved, intrinsics)
    x, y = _unpack(solved)
    rms_px, residual_mm = _hand_eye_figures(views, intrinsics, x, y)
    return HandEyeSolution(y, x, rms_px, residual_mm, intrinsics)


def _turn_z(angle_rad: float) -> FloatArray:
    c, s = math.cos(angle_rad), math.sin(angle_rad)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


#: The table sheet's frame in a frame level with the table, face up: its z axis (into the sheet) points down.
_FACE_UP = np.diag([1.0, -1.0, -1.0])


def solve_on_table_plane(
    views: Sequence[BoardView],
    intrinsics: CameraIntrinsics,
    sheet: BoardObservation,
    start: HandEyeSolution,
    sheet_face_z_m: float = 0.0,
) -> HandEyeSolution:
    """Camera to base referenced to the table plane: the sheet fixes height and tilt, the arm the rest.

    ``sheet`` is the view of the table sheet, a board lying flat on the table top, its face at
    ``sheet_face_z_m`` in the base frame, its place and turn on the table unknown. Its pose in the
    camera (``T_C_S``) gives the table plane in the camera frame; the camera to base is then
    ``Y = S(psi, x, y) inv(T_C_S)`` with ``S`` the sheet on the table (turned by ``psi``, at ``x, y``,
    face up at ``sheet_face_z_m``). ``psi``, ``x``, ``y`` and the board on the tool (6) are fitted to
    the reprojection error of every corner of ``views`` through ``inv(Y) A_i X``, intrinsics held;
    ``start`` (``solve_eye_to_hand``'s answer, or the nominal camera and mount when those views are
    all level) starts it. The camera's height and tilt over the table, which the arm's kinematic
    error would otherwise decide, then come from the camera alone; the arm gives what only it can:
    where the base is in that plane.
    """
    check_view_count(len(views), minimum=3)
    T_C_S = board_pose(sheet, intrinsics)
    S0 = start.camera_to_base @ T_C_S
    level = S0.rotation @ _FACE_UP
    psi0 = math.atan2(level[1, 0], level[0, 0])

    def camera_to_base(p: FloatArray) -> Pose:
        on_table = Pose.from_rotation([p[1], p[2], sheet_face_z_m], _turn_z(float(p[0])) @ _FACE_UP)
        return on_table @ T_C_S.inverse()

    def unpack(p: FloatArray) -> tuple[Pose, Pose]:
        return _pose(p[3:6], p[6:9]), camera_to_base(p)

    def residuals(p: FloatArray) -> FloatArray:
        x, y = unpack(p)
        return _residuals(np.concatenate([_rvec(x.rotation), x.position_m, _rvec(y.rotation), y.position_m]),
                          views, intrinsics)  # fmt: skip

    x0 = start.board_to_tool
    p0 = np.concatenate([[psi0, S0.position_m[0], S0.position_m[1]], _rvec(x0.rotation), x0.position_m])
    solved = _levenberg_marquardt(residuals, p0, np.full(9, 1e-7))
    x, y = unpack(solved)
    rms_px, residual_mm = _hand_eye_figures(views, intrinsics, x, y)
    return HandEyeSolution(y, x, rms_px, residual_mm, intrinsics)
