"""From four image corners to the cube's pose in the world.

PnP on the top face's corners with the known edge length: ``cv2.SOLVEPNP_IPPE_SQUARE`` (the
planar start, exact for four coplanar points of a square) refined by Levenberg-Marquardt
(``cv2.solvePnPRefineLM``), then the paper's Eq. 1, ``T_W_O = T_W_C * T_C_O``, with the cube's
centre half an edge below the top face.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from bt_arrange.geometry import FloatArray, Pose, fold_yaw, rotation_z
from bt_arrange.robot import CameraIntrinsics


def square_object_points(edge_m: float) -> FloatArray:
    """The top face's corners in the face frame (z out of the cube), in IPPE_SQUARE's order."""
    h = edge_m / 2.0
    return np.array([[-h, h, 0.0], [h, h, 0.0], [h, -h, 0.0], [-h, -h, 0.0]])


@dataclass(frozen=True)
class FacePose:
    """The top face in the camera frame, and how well it explains the corners."""

    T_C_F: Pose
    reprojection_error_px: float


def solve_face_pose(
    corners_px: FloatArray, camera_matrix: FloatArray, edge_m: float, distortion: FloatArray | None = None
) -> FacePose | None:
    """PnP of a square face from its four corners (ordered as :func:`~.segmentation.order_corners`).

    Returns None when OpenCV finds no pose. The reprojection error is the RMS distance, in
    pixels, between the corners and the projected square.
    """
    object_points = square_object_points(edge_m)
    image_points = np.asarray(corners_px, dtype=np.float64).reshape(4, 1, 2)
    dist = np.zeros(5) if distortion is None else np.asarray(distortion, dtype=np.float64)
    ok, rvec, tvec = cv2.solvePnP(
        object_points, image_points, camera_matrix, dist, flags=cv2.SOLVEPNP_IPPE_SQUARE
    )
    if not ok:
        return None
    criteria = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_COUNT, 50, 1e-12)
    rvec, tvec = cv2.solvePnPRefineLM(object_points, image_points, camera_matrix, dist, rvec, tvec, criteria)
    projected, _ = cv2.projectPoints(object_points, rvec, tvec, camera_matrix, dist)
    error_px = float(
        np.sqrt(np.mean(np.sum((projected.reshape(4, 2) - image_points.reshape(4, 2)) ** 2, axis=1)))
    )
    rotation, _ = cv2.Rodrigues(rvec)
    return FacePose(Pose.from_rotation(tvec.ravel(), rotation), error_px)


def cube_centre_in_world(T_W_C: Pose, T_C_F: Pose, edge_m: float) -> Pose:
    """Eq. 1 for the cube's centre, with the yaw folded to the cube's 90-degree symmetry.

    The centre lies half an edge below the top face, along the face normal into the cube. The
    face frame's x axis is turned by a multiple of 90 degrees about the normal so that the
    returned yaw lies in ``[-45, 45)`` degrees: every such turn shows the same cube.
    """
    T_W_F = T_W_C @ T_C_F
    T_W_O = T_W_F @ Pose(np.array([0.0, 0.0, -edge_m / 2.0]))
    yaw_rad = T_W_O.yaw_rad
    quarter_turns = round((fold_yaw(yaw_rad) - yaw_rad) / (math.pi / 2.0))
    return Pose.from_rotation(T_W_O.position_m, T_W_O.rotation @ rotation_z(quarter_turns * math.pi / 2.0))


def tilt_deg(T_W_O: Pose) -> float:
    """Angle between the cube's up axis and the world's, in degrees (0 for a cube lying flat)."""
    return math.degrees(math.acos(float(np.clip(T_W_O.rotation[2, 2], -1.0, 1.0))))


def pixel_ray_world(
    intrinsics: CameraIntrinsics, T_W_C: Pose, pixel: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Origin and direction (not normalised; unit depth along the optical axis) of a pixel's ray."""
    u, v = float(pixel[0]), float(pixel[1])
    ray_camera = np.array(
        [(u - intrinsics.cx_px) / intrinsics.fx_px, (v - intrinsics.cy_px) / intrinsics.fy_px, 1.0]
    )
    return T_W_C.position_m, T_W_C.rotation @ ray_camera


def pixel_on_plane(
    intrinsics: CameraIntrinsics, T_W_C: Pose, pixel: FloatArray, plane_z_m: float
) -> FloatArray | None:
    """The world point where a pixel's ray meets the horizontal plane ``z = plane_z_m``, or None."""
    origin, direction = pixel_ray_world(intrinsics, T_W_C, pixel)
    if abs(direction[2]) < 1e-9:
        return None
    scale = (plane_z_m - origin[2]) / direction[2]
    return origin + scale * direction if scale > 0 else None


def project_world(intrinsics: CameraIntrinsics, T_W_C: Pose, points_world: FloatArray) -> FloatArray:
    """Pinhole projection (distortion ignored) of world points (Nx3) to pixels (Nx2)."""
    points = np.atleast_2d(np.asarray(points_world, dtype=float))
    in_camera = (points - T_W_C.position_m) @ T_W_C.rotation
    return np.column_stack(
        [
            intrinsics.fx_px * in_camera[:, 0] / in_camera[:, 2] + intrinsics.cx_px,
            intrinsics.fy_px * in_camera[:, 1] / in_camera[:, 2] + intrinsics.cy_px,
        ]
    )


def expected_face_area_px(
    intrinsics: CameraIntrinsics, T_W_C: Pose, centre_world: FloatArray, edge_m: float
) -> float:
    """Image area of a level square face of ``edge_m`` centred at ``centre_world``, in pixels.

    Projects the square's corners, so it holds for any camera pose, not only straight down.
    """
    h = edge_m / 2.0
    corners = np.asarray(centre_world, dtype=float) + np.array(
        [[-h, -h, 0.0], [h, -h, 0.0], [h, h, 0.0], [-h, h, 0.0]]
    )
    p = project_world(intrinsics, T_W_C, corners)
    return 0.5 * abs(float(np.sum(p[:, 0] * np.roll(p[:, 1], -1) - np.roll(p[:, 0], -1) * p[:, 1])))
