"""From four image corners to the part's pose in the world.

Two models, chosen with :class:`PoseModel`:

* ``FREE``, the paper's: PnP on the top face's corners with the known edge length, from the
  planar ``cv2.SOLVEPNP_IPPE_SQUARE`` solution and the homography start of
  ``SOLVEPNP_ITERATIVE`` (the paper names a direct linear transformation; for four coplanar
  points OpenCV starts from the plane's homography instead, as its DLT needs six points not all
  in one plane), refined by Levenberg-Marquardt (``cv2.solvePnPRefineLM``), then the paper's Eq. 1,
  ``T_W_O = T_W_C * T_C_O``, with the part's centre half an edge below the top face.
* ``RESTING``, the default: a part on the table has its top face at a known height, so each
  corner's ray meets that plane at the corner itself; a square of the known edge fitted to
  the four points gives x, y and yaw. PnP of four points seen head-on cannot tell a slightly
  larger face from a nearer or tilted one, and turns a quarter-pixel error in the face's size
  into millimetres sideways; the plane fit cannot. PnP still runs, for its tilt and pose as
  quality figures.
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import cv2
import numpy as np

from bt_arrange.deprecation import renamed_attributes
from bt_arrange.geometry import FloatArray, Pose, fold_yaw, rotation_z
from bt_arrange.robot import CameraIntrinsics


class PoseModel(str, enum.Enum):
    """Which model of the part turns its corners into a pose."""

    #: The part rests flat on the table, so its top face lies at a known height: x, y and yaw
    #: from the corners' rays meeting that plane. Robust to errors in the face's apparent size.
    RESTING = "resting"
    #: Any 6-DoF pose, from PnP alone (the paper's method): also sees a tilted or lifted part,
    #: but a face seen head-on turns a size error of a fraction of a pixel into a tilt and a
    #: sideways shift of millimetres.
    FREE = "free"


def square_object_points(edge_m: float, other_edge_m: float | None = None) -> FloatArray:
    """The top face's corners in the face frame (z out of the part), in the order of the corners.

    Seen from above, like the camera sees them, they run clockwise on screen: the order of
    :func:`~bt_arrange.perception.segmentation.order_corners`. ``other_edge_m`` (default
    ``edge_m``) is a rectangle's y edge; the first side (corner 0 to 1) runs along x.
    """
    hx = edge_m / 2.0
    hy = hx if other_edge_m is None else other_edge_m / 2.0
    return np.array([[-hx, hy, 0.0], [hx, hy, 0.0], [hx, -hy, 0.0], [-hx, -hy, 0.0]])


def match_rectangle_sides(points: FloatArray, edge_m: float, other_edge_m: float | None) -> FloatArray:
    """The four corners rolled by one when that makes the first side (0 to 1) the x edge.

    A square needs no roll. For a rectangle, the pair of sides nearer the x edge's length in
    proportion is the x pair (``points`` in metres on a plane, or pixels: only ratios count).
    """
    if other_edge_m is None or abs(edge_m - other_edge_m) < 1e-9:
        return points
    pts = np.asarray(points, dtype=float)
    sides = np.linalg.norm(pts - np.roll(pts, -1, axis=0), axis=1)
    first, second = sides[0] + sides[2], sides[1] + sides[3]
    # x pair first when the first pair's share of the perimeter is nearer x's share.
    share_x = edge_m / (edge_m + other_edge_m)
    keep = abs(first / (first + second) - share_x) <= abs(second / (first + second) - share_x)
    return pts if keep else np.roll(pts, -1, axis=0)


#: Turns the face frame by 180 degrees about its x axis: z out of the part <-> z into it.
_FLIP_X = Pose.from_rotation(np.zeros(3), np.diag([1.0, -1.0, -1.0]))


@dataclass(frozen=True)
class FacePose:
    """The top face in the camera frame (z out of the part), and how well it explains the corners."""

    T_C_F: Pose
    reprojection_error_px: float


def _rms_px(projected: FloatArray, measured: FloatArray) -> float:
    return float(np.sqrt(np.mean(np.sum((projected.reshape(-1, 2) - measured.reshape(-1, 2)) ** 2, axis=1))))


def solve_face_pose(
    corners_px: FloatArray,
    camera_matrix: FloatArray,
    edge_m: float,
    distortion: FloatArray | None = None,
    other_edge_m: float | None = None,
) -> FacePose | None:
    """PnP of a square face of known edge from its four corners (ordered as ``order_corners``).

    ``other_edge_m`` makes it a rectangle of ``edge_m`` (x) by ``other_edge_m`` (y); the corners are
    rolled so that the first side is the x edge (``match_rectangle_sides``). IPPE_SQUARE needs a
    square, so a rectangle starts from ITERATIVE alone.

    Starts from ``SOLVEPNP_IPPE_SQUARE`` (the planar solution) and from ``SOLVEPNP_ITERATIVE``,
    which for four coplanar points starts from the homography of the face's plane (the paper's
    "direct linear transformation": OpenCV's DLT proper needs six points not all in one plane),
    refines each with Levenberg-Marquardt and keeps the pose with the
    smaller RMS reprojection error, in pixels. OpenCV's IPPE returns a correct pose only when
    the object's z axis points away from the camera (a face seen from the front comes back
    wrong by up to hundreds of pixels, or NaN when exactly fronto-parallel): it is given the
    face from behind, with the corners in reverse order, and its pose flipped back. Returns
    None when no start gives a finite pose.
    """
    square = other_edge_m is None or abs(other_edge_m - edge_m) < 1e-9
    object_points = square_object_points(edge_m, None if square else other_edge_m)
    corners = np.asarray(corners_px, dtype=np.float64).reshape(4, 2)
    if not square:
        corners = match_rectangle_sides(corners, edge_m, other_edge_m)
    image_points = corners.reshape(4, 1, 2)
    dist = np.zeros(5) if distortion is None else np.asarray(distortion, dtype=np.float64)
    starts: list[tuple[FloatArray, FloatArray]] = []
    # Seen from behind, the face's corners run the other way round: reverse them, so that
    # IPPE_SQUARE's object points are the face frame turned by 180 degrees about x.
    behind = image_points[[3, 2, 1, 0]]
    count: int = 0
    rvecs: Any = []
    tvecs: Any = []
    if square:
        count, rvecs, tvecs, _ = cv2.solvePnPGeneric(
            object_points, behind, camera_matrix, dist, flags=cv2.SOLVEPNP_IPPE_SQUARE
        )
    for rvec, tvec in zip(rvecs[:count], tvecs[:count], strict=True):
        if not (np.all(np.isfinite(rvec)) and np.all(np.isfinite(tvec))):
            continue
        rotation, _ = cv2.Rodrigues(rvec)
        flipped = Pose.from_rotation(np.ravel(tvec), rotation) @ _FLIP_X
        starts.append((np.asarray(cv2.Rodrigues(flipped.rotation)[0], dtype=float), flipped.position_m.reshape(3, 1)))
    ok, rvec, tvec = cv2.solvePnP(object_points, image_points, camera_matrix, dist, flags=cv2.SOLVEPNP_ITERATIVE)
    if ok:
        starts.append((np.asarray(rvec, dtype=float), np.asarray(tvec, dtype=float)))
    criteria = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_COUNT, 50, 1e-12)
    best: FacePose | None = None
    for rvec, tvec in starts:
        if not (np.all(np.isfinite(rvec)) and np.all(np.isfinite(tvec))):
            continue
        rvec, tvec = cv2.solvePnPRefineLM(object_points, image_points, camera_matrix, dist, rvec, tvec, criteria)
        if not (np.all(np.isfinite(rvec)) and np.all(np.isfinite(tvec))):
            continue
        projected, _ = cv2.projectPoints(object_points, rvec, tvec, camera_matrix, dist)
        error_px = _rms_px(np.asarray(projected, dtype=float), image_points)
        # The face must lie in front of the camera, seen from outside the part.
        rotation, _ = cv2.Rodrigues(rvec)
        if tvec.ravel()[2] <= 0 or rotation[:, 2] @ tvec.ravel() >= 0:
            continue
        if best is None or error_px < best.reprojection_error_px:
            best = FacePose(Pose.from_rotation(tvec.ravel(), rotation), error_px)
    return best


@dataclass(frozen=True)
class PlaneFit:
    """A level square fitted to corners back-projected onto the plane of the top faces.

    ``centre_m`` is the face centre (x, y, z) in the world, ``yaw_rad`` the heading of its edges,
    ``edge_m`` the edge length the corners suggest (the known edge for a part resting on the
    table), ``reprojection_error_px`` the RMS distance between the corners and the projected
    square of the known edge.
    """

    centre_m: FloatArray
    yaw_rad: float
    edge_m: float
    reprojection_error_px: float


def fit_square_on_plane(
    corners_px: FloatArray,
    intrinsics: CameraIntrinsics,
    T_W_C: Pose,
    plane_z_m: float,
    edge_m: float,
    other_edge_m: float | None = None,
) -> PlaneFit | None:
    """x, y and yaw of a level square face on the plane ``z = plane_z_m`` from its four corners.

    For a part resting on the table the height of its top face is known, and each corner's ray
    meets that plane at the corner itself: a rigid 2D fit (Procrustes) of the known square to the
    four points gives the pose. Unlike 6-DoF PnP, an error in the face's apparent size cannot
    turn into a tilt or a depth, and so into a sideways shift of the centre. Corners are
    undistorted pixels. Returns None if a ray misses the plane.

    ``other_edge_m`` makes it a rectangle of ``edge_m`` along its x axis by ``other_edge_m``: the
    yaw is then that of the x edges, folded to 180 degrees (``edge_m`` of the result is the fitted
    x edge).
    """
    square = other_edge_m is None or abs(other_edge_m - edge_m) < 1e-9
    points = []
    for corner in np.asarray(corners_px, dtype=float).reshape(4, 2):
        point = pixel_on_plane(intrinsics, T_W_C, corner, plane_z_m)
        if point is None:
            return None
        points.append(point[:2])
    world = np.array(points)
    measured_px = np.asarray(corners_px, dtype=float).reshape(4, 2)
    if not square:
        rolled = match_rectangle_sides(world, edge_m, other_edge_m)
        if not np.array_equal(rolled, world):
            world, measured_px = rolled, np.roll(measured_px, -1, axis=0)
    hx = edge_m / 2.0
    hy = hx if square or other_edge_m is None else other_edge_m / 2.0
    model = np.array([[-hx, -hy], [hx, -hy], [hx, hy], [-hx, hy]])  # counter-clockwise seen from above
    if _signed_area(world) < 0:
        # Clockwise corners: the model's order reversed keeps its first side along x.
        model = np.array([[-hx, hy], [hx, hy], [hx, -hy], [-hx, -hy]])
    centre = world.mean(axis=0)
    relative = world - centre
    # Procrustes rotation: the angle that best turns the model's corners onto the measured ones.
    cross = float(np.sum(model[:, 0] * relative[:, 1] - model[:, 1] * relative[:, 0]))
    dot = float(np.sum(model[:, 0] * relative[:, 0] + model[:, 1] * relative[:, 1]))
    yaw_rad = math.atan2(cross, dot)
    rotated = model @ rotation_z(yaw_rad)[:2, :2].T
    scale = float(np.sum(rotated * relative) / np.sum(model * model))
    fitted = np.column_stack([rotated + centre, np.full(4, plane_z_m)])
    error_px = _rms_px(project_world(intrinsics, T_W_C, fitted), measured_px)
    symmetry = math.pi / 2 if square else math.pi
    return PlaneFit(np.array([centre[0], centre[1], plane_z_m]), fold_yaw(yaw_rad, symmetry), scale * edge_m, error_px)


def _signed_area(points: FloatArray) -> float:
    return 0.5 * float(np.sum(points[:, 0] * np.roll(points[:, 1], -1) - np.roll(points[:, 0], -1) * points[:, 1]))


def part_centre_in_world(T_W_C: Pose, T_C_F: Pose, edge_m: float, symmetry_rad: float = math.pi / 2) -> Pose:
    """Eq. 1 for the part's centre, with the yaw folded to the part's symmetry.

    The centre lies half an edge (``edge_m``: the height) below the top face, along the face normal
    into the part. The face frame's x axis is turned by a multiple of ``symmetry_rad`` (90 degrees
    for a square top, 180 for a rectangle) about the normal so that the returned yaw lies in
    ``[-symmetry/2, symmetry/2)``: every such turn shows the same part.
    """
    T_W_F = T_W_C @ T_C_F
    T_W_O = T_W_F @ Pose(np.array([0.0, 0.0, -edge_m / 2.0]))
    yaw_rad = T_W_O.yaw_rad
    turns = round((fold_yaw(yaw_rad, symmetry_rad) - yaw_rad) / symmetry_rad)
    return Pose.from_rotation(T_W_O.position_m, T_W_O.rotation @ rotation_z(turns * symmetry_rad))


def tilt_deg(T_W_O: Pose) -> float:
    """Angle between the part's up axis and the world's, in degrees (0 for a part lying flat)."""
    return math.degrees(math.acos(float(np.clip(T_W_O.rotation[2, 2], -1.0, 1.0))))


def pixel_ray_world(intrinsics: CameraIntrinsics, T_W_C: Pose, pixel: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Origin and direction (not normalised; unit depth along the optical axis) of a pixel's ray."""
    u, v = float(pixel[0]), float(pixel[1])
    ray_camera = np.array([(u - intrinsics.cx_px) / intrinsics.fx_px, (v - intrinsics.cy_px) / intrinsics.fy_px, 1.0])
    return T_W_C.position_m, T_W_C.rotation @ ray_camera


def pixel_on_plane(intrinsics: CameraIntrinsics, T_W_C: Pose, pixel: FloatArray, plane_z_m: float) -> FloatArray | None:
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
    intrinsics: CameraIntrinsics,
    T_W_C: Pose,
    centre_world: FloatArray,
    edge_m: float,
    other_edge_m: float | None = None,
) -> float:
    """Image area of a level square face of ``edge_m`` (by ``other_edge_m``) centred at ``centre_world``, in pixels.

    Projects the face's corners, so it holds for any camera pose, not only straight down.
    """
    h = edge_m / 2.0
    k = h if other_edge_m is None else other_edge_m / 2.0
    corners = np.asarray(centre_world, dtype=float) + np.array([[-h, -k, 0.0], [h, -k, 0.0], [h, k, 0.0], [-h, k, 0.0]])
    p = project_world(intrinsics, T_W_C, corners)
    return 0.5 * abs(float(np.sum(p[:, 0] * np.roll(p[:, 1], -1) - np.roll(p[:, 0], -1) * p[:, 1])))


def expected_outline_area_px(
    intrinsics: CameraIntrinsics, T_W_C: Pose, centre_world: FloatArray, outline_m: FloatArray
) -> float:
    """Image area of a level face of ``outline_m`` (N x 2, about its origin) at ``centre_world``, in pixels."""
    outline = np.asarray(outline_m, dtype=float)
    points = np.column_stack([outline, np.zeros(len(outline))]) + np.asarray(centre_world, dtype=float)
    p = project_world(intrinsics, T_W_C, points)
    return 0.5 * abs(float(np.sum(p[:, 0] * np.roll(p[:, 1], -1) - np.roll(p[:, 0], -1) * p[:, 1])))


# Deprecated: the names that said "cube" for any part, kept one release (CHANGELOG.md).
if TYPE_CHECKING:
    cube_centre_in_world = part_centre_in_world
else:
    __getattr__ = renamed_attributes(__name__, {"cube_centre_in_world": "part_centre_in_world"})


def undistorted(intrinsics: CameraIntrinsics, pixels: FloatArray) -> FloatArray:
    """Raw image pixels (N x 2) where the pinhole would see them: the lens's distortion taken out.

    A calibrated camera's frames carry its distortion (``CalibratedCamera``). The held look stands
    0.3 m off the camera's axis, where the calibrated real-cell model's lens moves a pixel 2 to 3 %
    towards the centre: ignored, a held fresco piece was measured 5.5 to 6.7 mm off towards the axis,
    and placed that far off. The detector's edge fit takes its points through it too.
    """
    if not any(abs(k) > 0 for k in intrinsics.distortion) or len(pixels) == 0:
        return pixels
    matrix = intrinsics.matrix
    points = np.asarray(pixels, dtype=np.float64).reshape(-1, 1, 2)
    pinhole = cv2.undistortPoints(points, matrix, np.asarray(intrinsics.distortion, dtype=float), P=matrix)
    return np.asarray(pinhole, dtype=np.float64).reshape(-1, 2)


def distorted(intrinsics: CameraIntrinsics, pixels: FloatArray) -> FloatArray:
    """Pinhole pixels (N x 2) where the lens puts them in the raw image (``undistorted``'s inverse)."""
    if not any(abs(k) > 0 for k in intrinsics.distortion) or len(pixels) == 0:
        return pixels
    normalised = np.column_stack(
        [
            (pixels[:, 0] - intrinsics.cx_px) / intrinsics.fx_px,
            (pixels[:, 1] - intrinsics.cy_px) / intrinsics.fy_px,
            np.ones(len(pixels)),
        ]
    )
    raw, _ = cv2.projectPoints(
        normalised.reshape(-1, 1, 3),
        np.zeros(3),
        np.zeros(3),
        intrinsics.matrix,
        np.asarray(intrinsics.distortion, dtype=float),
    )
    return np.asarray(raw, dtype=np.float64).reshape(-1, 2)
