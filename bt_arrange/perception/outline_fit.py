"""Registering a known outline to points on the table plane: the outline model, the coarse yaw, ICP.

Everything here works in metres on the plane of the top faces, on points the image side
(``bt_arrange.perception.outline``) has taken there; nothing here reads an image.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree

from bt_arrange.geometry import FloatArray, Pose
from bt_arrange.objects import ObjectType
from bt_arrange.perception.corners import _median
from bt_arrange.robot import CameraIntrinsics

#: The coarse yaw grid (degrees) and how many contour points it scores.
COARSE_STEP_DEG = 2.0
COARSE_POINTS = 160
#: The contour points the ICP fits (evenly spaced along it).
ICP_POINTS = 320
#: Two yaws this far apart (after folding to the symmetry) are different registrations.
DISTINCT_YAW_DEG = 10.0
#: The sub-pixel passes: (band half width, px; margin at the edge's ends, px), as the box's.
EDGE_PASSES: tuple[tuple[int, float], ...] = ((5, 3.0), (4, 3.0))
#: Fewer edge points than this on an edge: the edge is left out of the fit.
MIN_EDGE_POINTS = 5
#: An edge point's distance counts up to this much (px) in ``OutlineFit.misfit_px``: a stray point
#: (a speck, a neighbour's edge) weighs no more than a point on an edge a pixel and a half away.
MISFIT_CAP_PX = 1.5


@dataclass(frozen=True)
class OutlineModel:
    """A known outline, ready to register.

    The part, its outline (counter-clockwise about the centroid, metres), height and symmetry, and
    its edges (start, unit direction, length, outward normal and the normal's offset ``n . a``).
    """

    part: ObjectType
    outline_m: FloatArray
    height_m: float
    symmetry_rad: float
    area_m2: float
    starts: FloatArray
    directions: FloatArray
    lengths: FloatArray
    normals: FloatArray
    offsets: FloatArray
    #: Per vertex: how far (metres, before scaling by the morphology's radius) its rounding reaches.
    corner_sharpness: FloatArray

    @classmethod
    def of(cls, part: ObjectType) -> OutlineModel:
        """The model of a part's outline, any shape."""
        prism = part.shape
        outline = np.asarray(prism.outline_m, dtype=float)
        vectors = np.roll(outline, -1, axis=0) - outline
        lengths = np.hypot(vectors[:, 0], vectors[:, 1])
        directions = vectors / lengths[:, None]
        normals = np.column_stack([directions[:, 1], -directions[:, 0]])  # right of travel: outward
        offsets = np.einsum("ij,ij->i", normals, outline)
        # The interior angle at each vertex; the morphology rounds a corner of angle b (the
        # sharper of the face's and the outside's) out to r / sin(b / 2) from the vertex.
        before, after = -np.roll(directions, 1, axis=0), directions
        angles = np.arccos(np.clip(np.einsum("ij,ij->i", before, after), -1.0, 1.0))
        sharp = np.minimum(angles, 2 * math.pi - angles)
        sharpness = 1.0 / np.maximum(np.sin(sharp / 2), 0.05)
        return cls(
            part,
            outline,
            float(prism.height_m),
            float(prism.symmetry_rad),
            float(prism.area_m2),
            outline,
            directions,
            lengths,
            normals,
            offsets,
            sharpness,
        )

    @property
    def name(self) -> str:
        """The part's name."""
        return self.part.name

    def posed(self, x_m: float, y_m: float, yaw_rad: float) -> FloatArray:
        """The outline on the table (N x 2) with its centroid at ``(x, y)`` turned by ``yaw_rad``."""
        c, s = math.cos(yaw_rad), math.sin(yaw_rad)
        return self.outline_m @ np.array([[c, s], [-s, c]]) + np.array([x_m, y_m])


@dataclass(frozen=True)
class OutlineFit:
    """A registration of an outline to a face: the pose on the table and how well it explains the face.

    ``deviation_px`` is the largest distance, either way, between the mask's contour and the fitted
    outline away from the corners; ``rms_px`` the RMS distance of the sub-pixel edge points from
    the model's edges (None for a coarse fit only); ``edge_points`` how many were used.
    """

    model: OutlineModel
    x_m: float
    y_m: float
    yaw_rad: float
    deviation_px: float
    rms_px: float | None = None
    edge_points: int = 0
    #: The RMS distance of *all* the measured edge points from the model's edges, each capped at
    #: ``MISFIT_CAP_PX``: unlike ``rms_px`` nothing is trimmed, so a wrong yaw cannot hide its misfit.
    misfit_px: float | None = None


# -- geometry on the plane ---------------------------------------------------------------------


def pixels_on_plane(intrinsics: CameraIntrinsics, T_W_C: Pose, pixels: FloatArray, plane_z_m: float) -> FloatArray:
    """World (x, y) where the rays of undistorted ``pixels`` (N x 2) meet ``z = plane_z_m`` (N x 2).

    A ray that misses the plane (parallel to it, or meeting it behind the camera) gives NaN.
    """
    pixels = np.asarray(pixels, dtype=float).reshape(-1, 2)
    rays = (
        np.column_stack(
            [
                (pixels[:, 0] - intrinsics.cx_px) / intrinsics.fx_px,
                (pixels[:, 1] - intrinsics.cy_px) / intrinsics.fy_px,
                np.ones(len(pixels)),
            ]
        )
        @ T_W_C.rotation.T
    )
    origin = T_W_C.position_m
    with np.errstate(divide="ignore", invalid="ignore"):
        scale = (plane_z_m - origin[2]) / rays[:, 2]
    scale = np.where(scale > 0, scale, np.nan)
    return origin[:2] + scale[:, None] * rays[:, :2]


def segment_distances(points: FloatArray, model: OutlineModel | EdgeSegments) -> tuple[FloatArray, FloatArray]:
    """Distances (..., M, N) from points (..., M, 2) in the model's frame to each edge, and where along it (0..1)."""
    squared, t = _segment_squared(points, model)
    return np.sqrt(squared), t


def nearest_segment_distances(points: FloatArray, model: OutlineModel | EdgeSegments) -> FloatArray:
    """Distances (..., M) from points (..., M, 2) to the nearest edge: ``segment_distances(...)[0].min(axis=-1)``.

    The square root is taken of the least square only (the same values: the root is monotonic),
    which is most of the coarse yaw search's work saved.
    """
    # One edge at a time, so the arrays stay in the processor's cache (the same values, the same
    # arithmetic per element as ``_segment_squared``).
    x, y = points[..., 0], points[..., 1]
    least = np.full(x.shape, np.inf)
    for start, direction, length in zip(model.starts, model.directions, model.lengths, strict=True):
        px, py = x - start[0], y - start[1]
        along = px * direction[0] + py * direction[1]
        tl = np.clip(along / length, 0.0, 1.0) * length
        np.minimum(least, px * px + py * py - 2 * tl * along + tl * tl, out=least)
    return np.sqrt(np.maximum(least, 0.0))


def _segment_squared(points: FloatArray, model: OutlineModel | EdgeSegments) -> tuple[FloatArray, FloatArray]:
    # The two coordinates apart: the same products and sums as a contraction over them, without
    # einsum's set-up for every call (most calls hold a few hundred points).
    px = points[..., :, 0, None] - model.starts[:, 0]  # (..., M, N)
    py = points[..., :, 1, None] - model.starts[:, 1]
    along = px * model.directions[:, 0] + py * model.directions[:, 1]
    t = np.clip(along / model.lengths, 0.0, 1.0)
    # |p - a - t L d|^2 = |p - a|^2 - 2 t L (p - a).d + (t L)^2
    tl = t * model.lengths
    squared = px * px + py * py - 2 * tl * along + tl * tl
    return np.maximum(squared, 0.0), t


@dataclass(frozen=True)
class EdgeSegments:
    """Straight segments: starts (N x 2), unit directions and lengths."""

    starts: FloatArray
    directions: FloatArray
    lengths: FloatArray

    @classmethod
    def closed(cls, points: FloatArray) -> EdgeSegments:
        """The edges of a closed polygon through ``points``."""
        vectors = np.roll(points, -1, axis=0) - points
        lengths = np.maximum(np.hypot(vectors[:, 0], vectors[:, 1]), 1e-12)
        return cls(points, vectors / lengths[:, None], lengths)


def _to_model(points: FloatArray, x_m: float, y_m: float, yaw_rad: float) -> FloatArray:
    c, s = math.cos(yaw_rad), math.sin(yaw_rad)
    return (points - np.array([x_m, y_m])) @ np.array([[c, -s], [s, c]])


def area_centroid(points: FloatArray) -> tuple[float, FloatArray]:
    """A polygon's signed area and area centroid."""
    x, y = points[:, 0], points[:, 1]
    xn, yn = np.roll(x, -1), np.roll(y, -1)
    cross = x * yn - xn * y
    area = 0.5 * float(np.sum(cross))
    if abs(area) < 1e-12:
        return 0.0, points.mean(axis=0)
    cx = float(np.sum((x + xn) * cross)) / (6 * area)
    cy = float(np.sum((y + yn) * cross)) / (6 * area)
    return abs(area), np.array([cx, cy])


def resample(points: FloatArray, count: int) -> FloatArray:
    """``count`` points evenly spaced by arc length along a closed polyline."""
    closed = np.vstack([points, points[:1]])
    steps = np.hypot(*np.diff(closed, axis=0).T)
    arc = np.concatenate([[0.0], np.cumsum(steps)])
    targets = np.linspace(0.0, arc[-1], count, endpoint=False)
    return np.column_stack([np.interp(targets, arc, closed[:, 0]), np.interp(targets, arc, closed[:, 1])])


def coarse_yaws(points_m: FloatArray, centre_m: FloatArray, model: OutlineModel, cap_m: float) -> list[float]:
    """Yaws on the coarse grid over one symmetry turn, best first: the local minima of the contour's score.

    The score of a yaw is the mean of ``min(d, cap)^2`` over the contour points, ``d`` the point's
    distance to the outline turned by that yaw about ``centre_m``.
    """
    turn = min(model.symmetry_rad, 2 * math.pi)
    count = max(1, int(round(math.degrees(turn) / COARSE_STEP_DEG)))
    yaws = np.arange(count) * (turn / count)
    relative = points_m - centre_m
    c, s = np.cos(yaws), np.sin(yaws)
    # Each point into the model's frame for every yaw: R(-yaw) p.
    local = np.stack(
        [
            c[:, None] * relative[None, :, 0] + s[:, None] * relative[None, :, 1],
            -s[:, None] * relative[None, :, 0] + c[:, None] * relative[None, :, 1],
        ],
        axis=-1,
    )
    scores = np.mean(np.minimum(nearest_segment_distances(local, model), cap_m) ** 2, axis=-1)
    minima = [k for k in range(count) if scores[k] <= scores[k - 1] and scores[k] <= scores[(k + 1) % count]]
    return [float(yaws[k]) for k in sorted(minima, key=lambda k: scores[k])]


def edge_residuals_m(
    points_m: FloatArray, edge: NDArray[np.intp], model: OutlineModel, pose: tuple[float, float, float]
) -> FloatArray:
    """Each point's signed distance (metres, outward positive) from the line of its edge, the outline at ``pose``."""
    x, y, yaw = pose
    c, s = math.cos(yaw), math.sin(yaw)
    normals = model.normals[edge]
    world_normals = np.column_stack([c * normals[:, 0] - s * normals[:, 1], s * normals[:, 0] + c * normals[:, 1]])
    return np.einsum("ij,ij->i", world_normals, points_m - np.array([x, y])) - model.offsets[edge]


def gauss_newton(
    points_m: FloatArray,
    edge: NDArray[np.intp],
    model: OutlineModel,
    pose: tuple[float, float, float],
    trim_floor_m: float,
    iterations: int = 8,
) -> tuple[tuple[float, float, float], FloatArray]:
    """Trimmed least squares of the points' distances to their edges' lines over (x, y, yaw); the kept residuals."""
    x, y, yaw = pose
    # Coordinates apart, as in ``segment_distances``: the arithmetic of the vector form, with less
    # of numpy's set-up per call (the ICPs call this thousands of times a run on a few hundred points).
    normal_x, normal_y, offsets = model.normals[edge, 0], model.normals[edge, 1], model.offsets[edge]
    points_x, points_y = points_m[:, 0], points_m[:, 1]
    keep = np.ones(len(points_m), dtype=bool)
    residual = np.zeros(len(points_m))
    for _ in range(iterations):
        c, s = math.cos(yaw), math.sin(yaw)
        world_x, world_y = c * normal_x - s * normal_y, s * normal_x + c * normal_y
        relative_x, relative_y = points_x - x, points_y - y
        residual = world_x * relative_x + world_y * relative_y - offsets
        size = np.abs(residual)
        limit = max(3.5 * 1.4826 * median_1d(size[keep]), trim_floor_m)
        keep = size <= limit
        if np.count_nonzero(keep) < 3:
            break
        # The Jacobian's kept rows only: the same values as the whole one's rows, a fraction of the work.
        kx, ky, rx, ry = world_x[keep], world_y[keep], relative_x[keep], relative_y[keep]
        jacobian = np.column_stack([-kx, -ky, rx * -ky + ry * kx])
        step, *_ = np.linalg.lstsq(jacobian, -residual[keep], rcond=None)
        dx, dy, dyaw = float(step[0]), float(step[1]), float(step[2])
        x, y, yaw = x + dx, y + dy, yaw + dyaw
        if max(abs(dx), abs(dy), abs(dyaw)) < 1e-9:
            break
    return (x, y, yaw), residual[keep]


def median_1d(values: FloatArray) -> float:
    """``float(_median(values))`` of a flat array, by a partial sort: the same value, in a fraction of the time."""
    count = len(values)
    if count == 0 or np.isnan(values).any():
        return float(_median(values))
    middle = np.partition(values, ((count - 1) // 2, count // 2))
    return float((middle[(count - 1) // 2] + middle[count // 2]) / 2)


def icp(
    points_m: FloatArray,
    model: OutlineModel,
    pose: tuple[float, float, float],
    trim_floor_m: float,
    rounds: int = 6,
    *,
    corner_share: float = 0.0,
    yaw_lever_m: float = 0.0,
) -> tuple[float, float, float]:
    """Point-to-line ICP of contour points on the plane: each point to its nearest edge's line, re-assigned each round.

    Points whose nearest place on the outline is a vertex (the rounded corners), or within
    ``corner_share`` of an edge's length from one, are left out. The rounds end once a round moves
    the pose less than a micrometre; with ``yaw_lever_m`` its turn counts too, as the arc at that radius.
    """
    for _ in range(rounds):
        local = _to_model(points_m, *pose)
        distances, t = segment_distances(local, model)
        edge = np.argmin(distances, axis=1)
        along = t[np.arange(len(edge)), edge]
        inner = (along > corner_share) & (along < 1.0 - corner_share)
        if inner.sum() < 6:
            break
        new_pose, _ = gauss_newton(points_m[inner], edge[inner], model, pose, trim_floor_m, iterations=3)
        moved = max(abs(new_pose[0] - pose[0]), abs(new_pose[1] - pose[1]), abs(new_pose[2] - pose[2]) * yaw_lever_m)
        pose = new_pose
        if moved < 1e-6:
            break
    return pose


def outline_deviation_m(
    contour_m: FloatArray, model: OutlineModel, pose: tuple[float, float, float], rounding_m: float
) -> float:
    """The largest distance, either way, between the contour (on the plane) and the posed outline, away from corners.

    Near each vertex the morphology rounds the mask by up to ``rounding_m / sin(b / 2)`` (``b`` the
    corner's sharper angle): contour points and outline samples within that, plus ``rounding_m``,
    of a vertex are not counted (but never more than 40 % of the edges meeting there).
    """
    local = _to_model(contour_m, *pose)
    zone = (model.corner_sharpness + 1.0) * rounding_m
    zone = np.minimum(zone, 0.4 * np.minimum(model.lengths, np.roll(model.lengths, 1)))
    to_vertex = np.hypot(*(local[:, None, :] - model.outline_m[None, :, :]).transpose(2, 0, 1))
    away = np.all(to_vertex > zone[None, :], axis=1)
    distances, _ = segment_distances(local[away], model)
    outward = float(distances.min(axis=1).max()) if away.any() else 0.0
    # The outline's samples to the contour: a missing piece of the face shows here.
    samples = []
    step = rounding_m / 2
    for k in range(len(model.outline_m)):
        s_values = np.arange(zone[k], model.lengths[k] - zone[(k + 1) % len(zone)], step)
        samples.append(model.starts[k] + s_values[:, None] * model.directions[k])
    points = np.vstack(samples) if samples else np.empty((0, 2))
    if len(points) == 0:
        return outward
    # The contour's pixels are at most a pixel and a half apart: its nearest point is near enough.
    # A k-d tree of the contour finds it (SciPy's cKDTree) where a scan over the contour did.
    nearest, _ = cKDTree(local).query(points)
    inward = float(np.max(nearest))
    return max(outward, inward)


# -- the face seen in one frame ----------------------------------------------------------------
