"""The pose of a part held in the fingers, from the top camera: its outline where the gripper leaves it in view.

A part held under the gripper is seen only in part: the gripper's body, its fingers and the arm's
wrist stand above it and hide the rest. :func:`measure_held` takes a frame with depth, keeps the
pixels of the part's colour whose surface lies on the plane of its top face (the depth says so: a
part on the table below, of the same colour, is not counted), and takes as its outline only the
edge pixels with nothing higher than that face beside them: an edge against the gripper's pixels
is where the part is hidden, not where it ends. Those points, on the plane of the top face, are
registered to the part's known outline (point-to-line ICP from several starts around where the
grasp put it), and the fit is trusted only when

- enough outline is seen, and on edges that fix x, y and yaw (the fit's own covariance, from the
  points' scatter, stays under ``max_sigma_mm`` and ``max_sigma_deg``);
- the points lie on the fitted outline (RMS under ``max_rms_mm``) and the outline predicted in view
  (not under the gripper) is where edges were seen (``max_missing``);
- the pose lies within ``max_shift_mm`` and ``max_turn_deg`` of where the grasp expected it.

Anything else is an untrusted measurement with its reason: the caller sets the part down and looks
at it on the table instead.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from bt_arrange.geometry import FloatArray, PlanarPose, fold_yaw
from bt_arrange.perception.colours import ColourRange
from bt_arrange.perception.outline_fit import (
    OutlineModel,
    _to_model,
    icp,
    nearest_segment_distances,
    pixels_on_plane,
    segment_distances,
)
from bt_arrange.perception.pose import distorted, project_world, undistorted
from bt_arrange.perception.segmentation import colour_mask
from bt_arrange.robot import CameraFrame

#: A pixel whose surface lies this far (m) above the top face is the gripper's or the arm's.
ABOVE_FACE_M = 0.004
#: A pixel of the part's colour within this (m) of the top face's plane is the held part's top.
ON_FACE_M = 0.006
#: An edge pixel this close (px) to a higher surface, or to the window's border, is not the outline.
OCCLUSION_MARGIN_PX = 3
#: Starts of the ICP: shifts (m) in x and y around the expected pose, and turns (deg).
START_SHIFTS_M = (-0.024, -0.016, -0.008, 0.0, 0.008, 0.016, 0.024)
START_TURNS_DEG = (-6.0, 0.0, 6.0)
#: A point counts as on the outline within this (m); predicted outline without a point within it is missing.
ON_OUTLINE_M = 0.0015
#: The scatter of one edge point about its line (m) assumed for the fit's covariance: the rounding
#: of the pixel grid on the plane of a held part's top face (0.45 mm a pixel) and the edges' blur.
POINT_SIGMA_M = 0.0005


@dataclass(frozen=True)
class HeldMeasurement:
    """A held part's measured pose (world, its outline's centroid) and whether it can be trusted.

    ``pose`` is None when nothing was fitted; ``reason`` is empty when the measurement is trusted, else
    says why not. ``edge_points`` are the outline points seen, ``rms_mm`` their RMS distance from the
    fitted outline, ``sigma_mm`` / ``sigma_deg`` the fit's standard deviations, ``missing`` the
    fraction of the outline predicted in view where no edge was seen, ``seen`` the fraction of the
    outline's length in view.
    """

    pose: PlanarPose | None
    reason: str
    edge_points: int = 0
    rms_mm: float = math.inf
    sigma_mm: float = math.inf
    sigma_deg: float = math.inf
    missing: float = 1.0
    seen: float = 0.0

    @property
    def trusted(self) -> bool:
        """True when the pose may steer the placing."""
        return self.pose is not None and not self.reason


@dataclass(frozen=True)
class HeldLimits:
    """When a held part's measurement is trusted (see the module's docstring)."""

    min_points: int = 80
    max_rms_mm: float = 0.5
    max_sigma_mm: float = 0.8
    max_sigma_deg: float = 1.0
    max_missing: float = 0.1
    min_seen: float = 0.2
    max_shift_mm: float = 30.0
    max_turn_deg: float = 15.0


def outline_points(
    frame: CameraFrame, colour: ColourRange, plane_z_m: float
) -> tuple[FloatArray, np.ndarray, np.ndarray]:
    """The outline points of the part's top face on its plane (N x 2, world), and the masks (face, hidden)."""
    if frame.depth_m is None:
        raise ValueError("a held part is measured from a frame with depth")
    T_W_C = frame.camera_pose_world
    # The camera looks down: a surface's height is the camera's less its depth along the optical axis,
    # up to the camera's tilt (well under a millimetre of height over a window of a few centimetres).
    height_m = T_W_C.position_m[2] - frame.depth_m.astype(np.float64)
    on_face = np.abs(height_m - plane_z_m) < ON_FACE_M
    face = (colour_mask(frame.rgb, colour) > 0) & on_face
    hidden = height_m > plane_z_m + ABOVE_FACE_M
    kernel = np.ones((2 * OCCLUSION_MARGIN_PX + 1, 2 * OCCLUSION_MARGIN_PX + 1), np.uint8)
    near_hidden = cv2.dilate(hidden.astype(np.uint8), kernel) > 0
    contours, _ = cv2.findContours(face.astype(np.uint8), cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    if not contours:
        return np.zeros((0, 2)), face, near_hidden
    pixels = np.vstack([c.reshape(-1, 2) for c in contours if len(c) >= 8] or [np.zeros((0, 2), np.int32)])
    h, w = face.shape
    m = OCCLUSION_MARGIN_PX
    inside = (pixels[:, 0] >= m) & (pixels[:, 0] < w - m) & (pixels[:, 1] >= m) & (pixels[:, 1] < h - m)
    pixels = pixels[inside]
    pixels = pixels[~near_hidden[pixels[:, 1], pixels[:, 0]]]
    if len(pixels) == 0:
        return np.zeros((0, 2)), face, near_hidden
    points = pixels_on_plane(frame.intrinsics, T_W_C, undistorted(frame.intrinsics, pixels.astype(float)), plane_z_m)
    return points[np.isfinite(points).all(axis=1)], face, near_hidden


def _fit(points: FloatArray, model: OutlineModel, start: tuple[float, float, float]) -> tuple[float, float, float]:
    """The ICP of the held face's points from one start, corners' ends left out, its turn counted at 30 mm."""
    return icp(points, model, start, 0.001, rounds=8, corner_share=0.02, yaw_lever_m=0.03)


def fit_sigmas(jacobian: FloatArray) -> tuple[float, float]:
    """The fit's standard deviations (m in x or y, the larger; rad) from its point-to-line Jacobian (N x 3).

    Each point ``POINT_SIGMA_M`` about its line. Edges that leave a direction unfixed (one straight
    edge, parallel edges) give infinity, never a failure.
    """
    normal = jacobian.T @ jacobian
    eigenvalues = np.linalg.eigvalsh(normal)
    if not np.all(np.isfinite(eigenvalues)) or eigenvalues[0] <= 1e-9 * max(float(eigenvalues[-1]), 1e-300):
        return math.inf, math.inf
    variances = np.diag(np.linalg.inv(normal)) * POINT_SIGMA_M**2
    if not np.all(np.isfinite(variances)) or np.any(variances <= 0.0):
        return math.inf, math.inf
    return math.sqrt(max(float(variances[0]), float(variances[1]))), math.sqrt(float(variances[2]))


def _score(points: FloatArray, model: OutlineModel, pose: tuple[float, float, float]) -> float:
    return float(np.mean(np.minimum(nearest_segment_distances(_to_model(points, *pose), model), 0.004) ** 2))


def _scores(points: FloatArray, model: OutlineModel, poses: list[tuple[float, float, float]]) -> list[float]:
    """``_score`` of each pose, the poses' points stacked into one array: the same values, in one pass."""
    local = np.stack([_to_model(points, *pose) for pose in poses])
    return [float(v) for v in np.mean(np.minimum(nearest_segment_distances(local, model), 0.004) ** 2, axis=-1)]


def measure_held(
    frame: CameraFrame,
    colour: ColourRange,
    model: OutlineModel,
    plane_z_m: float,
    expected: PlanarPose,
    limits: HeldLimits | None = None,
) -> HeldMeasurement:
    """The held part's pose from ``frame`` (with depth), its top face at ``plane_z_m``, near ``expected``."""
    limits = limits or HeldLimits()
    points, _, near_hidden = outline_points(frame, colour, plane_z_m)
    if len(points) < limits.min_points:
        seen = f"{len(points)} outline points seen beside the gripper"
        return HeldMeasurement(None, f"{seen}, fewer than {limits.min_points}")
    # Points far from any place the part could be (another part, a reflection) are left out.
    reach = float(np.max(np.hypot(*model.outline_m.T))) + 0.035
    points = points[np.hypot(points[:, 0] - expected.x_m, points[:, 1] - expected.y_m) < reach]
    if len(points) < limits.min_points:
        return HeldMeasurement(None, f"{len(points)} outline points near the grasp, fewer than {limits.min_points}")
    starts = [
        (expected.x_m + dx, expected.y_m + dy, expected.yaw_rad + math.radians(turn))
        for dx in START_SHIFTS_M
        for dy in START_SHIFTS_M
        for turn in START_TURNS_DEG
    ]
    # The starts are ranked on about 120 of the points (the ranking only picks where the ICPs begin).
    few = points[:: max(1, len(points) // 120)]
    ranks = _scores(few, model, starts)
    scored = [starts[k] for k in sorted(range(len(starts)), key=ranks.__getitem__)[:4]]
    fits = [_fit(points, model, s) for s in scored]
    pose = min(fits, key=lambda p: _score(points, model, p))
    return _judge(frame, model, points, pose, plane_z_m, expected, near_hidden, limits)


def _judge(
    frame: CameraFrame,
    model: OutlineModel,
    points: FloatArray,
    pose: tuple[float, float, float],
    plane_z_m: float,
    expected: PlanarPose,
    near_hidden: np.ndarray,
    limits: HeldLimits,
) -> HeldMeasurement:
    x, y, yaw = pose
    measured = PlanarPose(x, y, yaw)
    local = _to_model(points, *pose)
    distances, t = segment_distances(local, model)
    edge = np.argmin(distances, axis=1)
    nearest = distances[np.arange(len(edge)), edge]
    on = nearest < ON_OUTLINE_M
    rms_mm = float(np.sqrt(np.mean(nearest[on] ** 2))) * 1000 if on.any() else math.inf
    # The fit's covariance from the points on the outline, each POINT_SIGMA_M about its edge's line.
    c, s = math.cos(yaw), math.sin(yaw)
    normals = model.normals[edge[on]]
    nx, ny = c * normals[:, 0] - s * normals[:, 1], s * normals[:, 0] + c * normals[:, 1]
    rx, ry = points[on, 0] - x, points[on, 1] - y
    sigma_m, sigma_rad = fit_sigmas(np.column_stack([nx, ny, -rx * ny + ry * nx]))
    # The outline where the camera should see it (in the frame, not under the gripper): was an edge seen there?
    outline = model.posed(x, y, yaw)
    closed = np.vstack([outline, outline[:1]])
    samples = np.vstack(
        [
            np.linspace(a, b, max(2, int(np.hypot(*(b - a)) / 0.001)), endpoint=False)
            for a, b in zip(closed[:-1], closed[1:], strict=True)
        ]
    )
    # Where the raw image shows the outline: the masks below are the raw image's.
    pixels = distorted(
        frame.intrinsics,
        project_world(
            frame.intrinsics, frame.camera_pose_world, np.column_stack([samples, np.full(len(samples), plane_z_m)])
        ),
    )
    h, w = near_hidden.shape
    m = OCCLUSION_MARGIN_PX
    u, v = np.round(pixels[:, 0]).astype(int), np.round(pixels[:, 1]).astype(int)
    in_frame = (u >= m) & (u < w - m) & (v >= m) & (v < h - m)
    in_view = np.zeros(len(samples), dtype=bool)
    in_view[in_frame] = ~near_hidden[v[in_frame], u[in_frame]]
    seen = float(in_view.mean())
    missing = 1.0
    if in_view.any():
        if on.any():
            visible, kept = samples[in_view], points[on]
            gaps = np.sqrt(np.min(((visible[:, None, :] - kept[None, :, :]) ** 2).sum(axis=-1), axis=1))
            missing = float(np.mean(gaps > ON_OUTLINE_M))
    shift_mm = math.hypot(x - expected.x_m, y - expected.y_m) * 1000
    turn_deg = abs(math.degrees(fold_yaw(yaw - expected.yaw_rad, model.symmetry_rad)))
    result = dict(
        edge_points=int(on.sum()),
        rms_mm=round(rms_mm, 3),
        sigma_mm=round(sigma_m * 1000, 3),
        sigma_deg=round(math.degrees(sigma_rad), 3),
        missing=round(missing, 3),
        seen=round(seen, 3),
    )
    reason = ""
    if on.sum() < limits.min_points:
        reason = f"{int(on.sum())} outline points on the fitted outline, fewer than {limits.min_points}"
    elif rms_mm > limits.max_rms_mm:
        reason = f"the outline points lie {rms_mm:.2f} mm RMS from the fitted outline, more than {limits.max_rms_mm:g}"
    elif sigma_m * 1000 > limits.max_sigma_mm or math.degrees(sigma_rad) > limits.max_sigma_deg:
        reason = (
            f"the edges in view fix the pose to {sigma_m * 1000:.2f} mm and {math.degrees(sigma_rad):.2f} deg, "
            f"more than {limits.max_sigma_mm:g} mm or {limits.max_sigma_deg:g} deg"
        )
    elif seen < limits.min_seen:
        reason = f"{seen:.0%} of the outline in view beside the gripper, less than {limits.min_seen:.0%}"
    elif missing > limits.max_missing:
        reason = f"no edge seen along {missing:.0%} of the fitted outline in view, more than {limits.max_missing:.0%}"
    elif shift_mm > limits.max_shift_mm or turn_deg > limits.max_turn_deg:
        reason = (
            f"{shift_mm:.1f} mm and {turn_deg:.1f} deg from where the grasp put it, more than "
            f"{limits.max_shift_mm:g} mm or {limits.max_turn_deg:g} deg"
        )
    return HeldMeasurement(measured, reason, **result)  # type: ignore[arg-type]
