"""Perception of outlines: a flat part's top face registered to its known outline.

A prism part (``bt_arrange.shapes.Prism``) has a top face of any simple polygon, convex or not,
at a known height. Its pose on the table (x, y of the area centroid, yaw) is found by
registering that outline to the face seen by the top camera, in three steps:

1. **The face**: the HSV mask of the colour, cleaned as for cubes, at full resolution on a crop
   around the blob; its Suzuki-Abe contour is taken onto the plane of the top faces (each
   pixel's ray meets ``z = table + height``), so the rest works in metres on the table.
2. **Coarse registration**, over the full circle of yaw (over one symmetry turn for a symmetric
   outline): the centre is the area centroid of the contour on the plane; every yaw on a 2
   degree grid is scored by the contour points' robust distance to the outline turned by it; the
   best, and the best of the yaws that are no symmetry turn of it, are refined by point-to-line
   ICP on the contour. The contour's two-sided deviation from the fitted outline, away from the
   corners the morphology rounds, says whether the face is this outline at all (another part,
   covered) and whether the second yaw fits as well (ambiguous).
3. **Sub-pixel edges**: each model edge of the coarse pose is measured below a pixel by the
   cube's method (``bt_arrange.perception.corners``: covered fractions unmixed in the chroma
   plane, summed across columns or rows), skipping where a band would reach another edge; the
   points are taken onto the plane and the 3-DoF pose is solved by trimmed least squares on
   their distances to the model's edge lines (Gauss-Newton on x, y and yaw). Two passes, like
   the cube's; the second reads the outside colour just beyond the measured edge spread.

Corners are never used: the mask's corners are rounded by the 7x7 morphology (by several
pixels at an acute corner), whereas every edge point between them is measured exactly.

``OutlineDetector`` (a ``CubeDetector``) tells parts of one colour apart by their outlines;
``CubeDetector.for_object(prism part)`` returns one, so ``Detect`` and ``Inspect`` need nothing
new. Perception stays free of the simulator.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace

import cv2
import numpy as np
from numpy.typing import NDArray

from bt_arrange.errors import PerceptionError
from bt_arrange.geometry import FloatArray, Pose, fold_yaw
from bt_arrange.objects import ObjectType
from bt_arrange.perception.colours import DEFAULT_COLOUR_TABLE, ColourRange, ColourTable
from bt_arrange.perception.corners import SHARP_EDGE_SPREAD, CornerRefinement, _median, _side_edge_points, chroma
from bt_arrange.perception.detection import CubeDetector, _View
from bt_arrange.perception.segmentation import Blob, colour_mask
from bt_arrange.perception.values import Detection, DetectionStatus, DetectorConfig, WorldRegion
from bt_arrange.robot import CameraFrame, CameraIntrinsics
from bt_arrange.shapes import Prism

#: The coarse yaw grid (degrees) and how many contour points it scores.
COARSE_STEP_DEG = 2.0
COARSE_POINTS = 160
#: The contour points the ICP fits (evenly spaced along it).
ICP_POINTS = 320
#: Two yaws this far apart (after folding to the symmetry) are different registrations.
DISTINCT_YAW_DEG = 10.0
#: The sub-pixel passes: (band half width, px; margin at the edge's ends, px), as the cube's.
EDGE_PASSES: tuple[tuple[int, float], ...] = ((5, 3.0), (4, 3.0))
#: Fewer edge points than this on an edge: the edge is left out of the fit.
MIN_EDGE_POINTS = 5


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
        """The model of a prism part; a ``PerceptionError`` for any other shape."""
        prism = part.shape
        if not isinstance(prism, Prism):
            raise PerceptionError(f"{part.name} is no prism ({prism.describe()})")
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


def _segment_distances(points: FloatArray, model: OutlineModel | _Segments) -> tuple[FloatArray, FloatArray]:
    """Distances (..., M, N) from points (..., M, 2) in the model's frame to each edge, and where along it (0..1)."""
    relative = points[..., None, :] - model.starts  # (..., M, N, 2)
    along = np.einsum("...nk,nk->...n", relative, model.directions)
    t = np.clip(along / model.lengths, 0.0, 1.0)
    # |p - a - t L d|^2 = |p - a|^2 - 2 t L (p - a).d + (t L)^2
    tl = t * model.lengths
    squared = np.einsum("...k,...k->...", relative, relative) - 2 * tl * along + tl * tl
    return np.sqrt(np.maximum(squared, 0.0)), t


@dataclass(frozen=True)
class _Segments:
    """Straight segments: starts (N x 2), unit directions and lengths."""

    starts: FloatArray
    directions: FloatArray
    lengths: FloatArray

    @classmethod
    def closed(cls, points: FloatArray) -> _Segments:
        """The edges of a closed polygon through ``points``."""
        vectors = np.roll(points, -1, axis=0) - points
        lengths = np.maximum(np.hypot(vectors[:, 0], vectors[:, 1]), 1e-12)
        return cls(points, vectors / lengths[:, None], lengths)


def _to_model(points: FloatArray, x_m: float, y_m: float, yaw_rad: float) -> FloatArray:
    c, s = math.cos(yaw_rad), math.sin(yaw_rad)
    return (points - np.array([x_m, y_m])) @ np.array([[c, -s], [s, c]])


def _area_centroid(points: FloatArray) -> tuple[float, FloatArray]:
    x, y = points[:, 0], points[:, 1]
    xn, yn = np.roll(x, -1), np.roll(y, -1)
    cross = x * yn - xn * y
    area = 0.5 * float(np.sum(cross))
    if abs(area) < 1e-12:
        return 0.0, points.mean(axis=0)
    cx = float(np.sum((x + xn) * cross)) / (6 * area)
    cy = float(np.sum((y + yn) * cross)) / (6 * area)
    return abs(area), np.array([cx, cy])


def _resample(points: FloatArray, count: int) -> FloatArray:
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
    distances, _ = _segment_distances(local, model)
    scores = np.mean(np.minimum(distances.min(axis=-1), cap_m) ** 2, axis=-1)
    minima = [k for k in range(count) if scores[k] <= scores[k - 1] and scores[k] <= scores[(k + 1) % count]]
    return [float(yaws[k]) for k in sorted(minima, key=lambda k: scores[k])]


def _gauss_newton(
    points_m: FloatArray,
    edge: NDArray[np.intp],
    model: OutlineModel,
    pose: tuple[float, float, float],
    trim_floor_m: float,
    iterations: int = 8,
) -> tuple[tuple[float, float, float], FloatArray]:
    """Trimmed least squares of the points' distances to their edges' lines over (x, y, yaw); the kept residuals."""
    x, y, yaw = pose
    normals, offsets = model.normals[edge], model.offsets[edge]
    keep = np.ones(len(points_m), dtype=bool)
    residual = np.zeros(len(points_m))
    for _ in range(iterations):
        c, s = math.cos(yaw), math.sin(yaw)
        world_normals = np.column_stack([c * normals[:, 0] - s * normals[:, 1], s * normals[:, 0] + c * normals[:, 1]])
        relative = points_m - np.array([x, y])
        residual = np.einsum("ij,ij->i", world_normals, relative) - offsets
        jacobian = np.column_stack(
            [
                -world_normals[:, 0],
                -world_normals[:, 1],
                np.einsum("ij,ij->i", relative, world_normals[:, ::-1] * [-1, 1]),
            ]
        )
        limit = max(3.5 * 1.4826 * float(_median(np.abs(residual[keep]))), trim_floor_m)
        keep = np.abs(residual) <= limit
        if keep.sum() < 3:
            break
        step, *_ = np.linalg.lstsq(jacobian[keep], -residual[keep], rcond=None)
        x, y, yaw = x + float(step[0]), y + float(step[1]), yaw + float(step[2])
        if float(np.max(np.abs(step))) < 1e-9:
            break
    return (x, y, yaw), residual[keep]


def icp(
    points_m: FloatArray, model: OutlineModel, pose: tuple[float, float, float], trim_floor_m: float, rounds: int = 6
) -> tuple[float, float, float]:
    """Point-to-line ICP of contour points on the plane: each point to its nearest edge's line, re-assigned each round.

    Points whose nearest place on the outline is a vertex (the rounded corners) are left out.
    """
    for _ in range(rounds):
        local = _to_model(points_m, *pose)
        distances, t = _segment_distances(local, model)
        edge = np.argmin(distances, axis=1)
        along = t[np.arange(len(edge)), edge]
        inner = (along > 0.0) & (along < 1.0)
        if inner.sum() < 6:
            break
        new_pose, _ = _gauss_newton(points_m[inner], edge[inner], model, pose, trim_floor_m, iterations=3)
        moved = max(abs(new_pose[0] - pose[0]), abs(new_pose[1] - pose[1]))
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
    distances, _ = _segment_distances(local[away], model)
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
    nearest = np.full(len(points), np.inf)
    for chunk in np.array_split(local, max(1, len(local) // 256)):
        gap = points[:, None, :] - chunk[None, :, :]
        nearest = np.minimum(nearest, np.einsum("ijk,ijk->ij", gap, gap).min(axis=1))
    inward = float(np.sqrt(nearest.max()))
    return max(outward, inward)


# -- the face seen in one frame ----------------------------------------------------------------


@dataclass(frozen=True)
class _Face:
    """One blob's face at full resolution: contour (image px), its area, on the plane, the face's chroma."""

    contour_px: NDArray[np.int32]
    area_px: float
    contour_m: FloatArray
    area_m2: float
    centroid_m: FloatArray
    face_chroma: FloatArray
    touches_border: bool


def _face(detector: CubeDetector, view: _View, colour: ColourRange, blob: Blob, plane_z_m: float) -> _Face | None:
    """The blob's face at full resolution, or None when it vanished."""
    height, width = view.rgb.shape[:2]
    x, y, w, h = blob.bbox_px
    margin = 12 + 2 * view.scale
    x0, y0 = max(0, x - margin), max(0, y - margin)
    x1, y1 = min(width, x + w + margin), min(height, y + h + margin)
    mask = colour_mask(view.rgb[y0:y1, x0:x1], colour, detector.config.kernel_px)
    contours, _ = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    if not contours:
        return None
    # The crop may catch pieces of other blobs: keep the region whose centroid is the blob's (a
    # non-convex face may not hold its own centroid).
    centre = np.array([blob.centroid_px[0] - x0, blob.centroid_px[1] - y0])

    def distance(contour: NDArray[np.int32]) -> float:
        moments = cv2.moments(contour)
        if moments["m00"] <= 0:
            return math.inf
        return float(np.hypot(moments["m10"] / moments["m00"] - centre[0], moments["m01"] / moments["m00"] - centre[1]))

    chosen = min(contours, key=lambda c: distance(np.asarray(c, dtype=np.int32)))
    contour = chosen.reshape(-1, 2) + np.array([x0, y0])
    area_px = float(cv2.contourArea(chosen))
    touches = bool(
        contour[:, 0].min() <= 0
        or contour[:, 1].min() <= 0
        or contour[:, 0].max() >= width - 1
        or contour[:, 1].max() >= height - 1
    )
    # The contour runs through the outermost mask pixels, about half a pixel inside the edge.
    points = contour.astype(float)
    if view.undistort is not None:
        points = view.undistort(points)
    on_plane = pixels_on_plane(view.intrinsics, view.T_W_C, points, plane_z_m)
    if not np.all(np.isfinite(on_plane)):
        return None
    area_m2, centroid = _area_centroid(on_plane)
    inner = np.zeros_like(mask)
    cv2.drawContours(inner, [chosen], -1, 255, thickness=cv2.FILLED)
    inner = np.asarray(cv2.erode(inner & mask, np.ones((5, 5), np.uint8)), dtype=np.uint8)
    v, u = np.nonzero(inner)
    if len(u) == 0:
        return None
    take = np.linspace(0, len(u) - 1, min(len(u), 400)).astype(int)
    face = _median(chroma(view.rgb[v[take] + y0, u[take] + x0]), axis=0)
    return _Face(contour, area_px, on_plane, area_m2, centroid, face, touches)


def _project(view: _View, points_world: FloatArray) -> FloatArray:
    """World points (N x 3) to raw image pixels (with the lens's distortion, if any)."""
    intrinsics = view.intrinsics
    if view.undistort is None:
        in_camera = (points_world - view.T_W_C.position_m) @ view.T_W_C.rotation
        return np.column_stack(
            [
                intrinsics.fx_px * in_camera[:, 0] / in_camera[:, 2] + intrinsics.cx_px,
                intrinsics.fy_px * in_camera[:, 1] / in_camera[:, 2] + intrinsics.cy_px,
            ]
        )
    T_C_W = view.T_W_C.inverse()
    rvec, _ = cv2.Rodrigues(T_C_W.rotation)
    projected, _ = cv2.projectPoints(
        points_world.reshape(-1, 1, 3),
        rvec,
        T_C_W.position_m.reshape(3, 1),
        intrinsics.matrix,
        np.asarray(intrinsics.distortion, dtype=float),
    )
    return np.asarray(projected, dtype=float).reshape(-1, 2)


def _edge_points(
    view: _View,
    face: _Face,
    model: OutlineModel,
    pose: tuple[float, float, float],
    plane_z_m: float,
    half_width_px: int,
    margin_px: float,
    near_outside_px: float | None,
) -> tuple[FloatArray, NDArray[np.intp], FloatArray]:
    """Sub-pixel points on the model's edges at ``pose``, on the plane (M x 2), their edge, and the edges' spreads."""
    posed = model.posed(*pose)
    count = len(posed)
    z = np.full((count, 1), plane_z_m)
    corners_px = _project(view, np.hstack([posed, z]))
    # A point just inside each edge's middle tells the edge sampler which side the face is.
    middles = (posed + np.roll(posed, -1, axis=0)) / 2
    c, s = math.cos(pose[2]), math.sin(pose[2])
    world_normals = model.normals @ np.array([[c, s], [-s, c]])
    inside_px = _project(view, np.hstack([middles - 0.002 * world_normals, z]))
    image_edges = _Segments.closed(corners_px)
    all_points, all_edges, spreads = [], [], []
    for k in range(count):
        p, q = corners_px[k], corners_px[(k + 1) % count]
        points, spread = _side_edge_points(
            view.rgb, p, q, inside_px[k], face.face_chroma, half_width_px, margin_px, near_outside_px
        )
        if len(points) == 0:
            continue
        # Keep the points whose band cannot reach another edge of the face.
        distances, _ = _segment_distances(points, image_edges)
        distances[:, k] = np.inf
        clear = distances.min(axis=1) >= half_width_px + 2.0
        points, spread = points[clear], spread[clear]
        if len(points) < MIN_EDGE_POINTS:
            continue
        if view.undistort is not None:
            points = view.undistort(points)
        all_points.append(pixels_on_plane(view.intrinsics, view.T_W_C, points, plane_z_m))
        all_edges.append(np.full(len(points), k, dtype=np.intp))
        spreads.append(spread)
    if not all_points:
        return np.empty((0, 2)), np.empty(0, dtype=np.intp), np.empty(0)
    return np.vstack(all_points), np.concatenate(all_edges), np.concatenate(spreads)


def _spans_two_directions(model: OutlineModel, edges: NDArray[np.intp]) -> bool:
    """True when the measured edges hold two directions at least 20 degrees apart (x, y and yaw are then fixed)."""
    used = np.unique(edges)
    if len(used) < 2:
        return False
    normals = model.normals[used]
    return float(np.min(np.abs(normals @ normals.T))) < math.cos(math.radians(20.0))


def register(
    view: _View,
    face: _Face,
    model: OutlineModel,
    plane_z_m: float,
    px_per_m: float,
    kernel_px: int,
    method: CornerRefinement = CornerRefinement.EDGE_LINES,
) -> tuple[OutlineFit | None, list[OutlineFit]]:
    """The coarse registrations of ``model`` to the face (best first), and the fine fit of the best.

    The fine fit is None when the edges could not be measured below a pixel. ``method`` chooses it
    (for comparison; docs/perception.md has the figures): ``EDGE_LINES``, sub-pixel edge points and
    least squares on the model's edge lines (the default); ``CORNER_SUBPIX``, ``cv2.cornerSubPix``
    at the outline's vertices on the face-coverage image and a rigid fit of the vertices;
    ``CONTOUR_LINES``, the contour's ICP alone; ``NONE``, the contour's centroid and the coarse grid's yaw.
    """
    metre = 1.0 / px_per_m
    points = _resample(face.contour_m, COARSE_POINTS)
    rounding_m = 0.5 * kernel_px * metre
    yaws = coarse_yaws(points, face.centroid_m, model, cap_m=6.0 * metre)
    contour_dense = face.contour_m
    icp_points = _resample(contour_dense, ICP_POINTS) if len(contour_dense) > ICP_POINTS else contour_dense
    fits: list[OutlineFit] = []
    for yaw in yaws[:3]:
        pose = icp(icp_points, model, (float(face.centroid_m[0]), float(face.centroid_m[1]), yaw), 0.3 * metre)
        folded = fold_yaw(pose[2], model.symmetry_rad)
        pose = (pose[0], pose[1], folded)
        if any(
            abs(fold_yaw(pose[2] - other.yaw_rad, model.symmetry_rad)) < math.radians(DISTINCT_YAW_DEG)
            for other in fits
        ):
            continue
        deviation = outline_deviation_m(contour_dense, model, pose, rounding_m) * px_per_m
        fits.append(OutlineFit(model, pose[0], pose[1], pose[2], deviation))
    fits.sort(key=lambda f: f.deviation_px)
    if not fits:
        return None, fits
    best = fits[0]
    if method is CornerRefinement.NONE:
        grid = yaws[0] if yaws else 0.0
        coarse = (float(face.centroid_m[0]), float(face.centroid_m[1]), fold_yaw(grid, model.symmetry_rad))
        return replace(best, x_m=coarse[0], y_m=coarse[1], yaw_rad=coarse[2], rms_px=0.0), fits
    if method is CornerRefinement.CONTOUR_LINES:
        return replace(best, rms_px=0.0), fits
    if method is CornerRefinement.CORNER_SUBPIX:
        return _corner_fit(view, face, best, plane_z_m, px_per_m), fits
    pose = (best.x_m, best.y_m, best.yaw_rad)
    near_outside_px: float | None = None
    residual = np.empty(0)
    edges = np.empty(0, dtype=np.intp)
    for half_width_px, margin_px in EDGE_PASSES:
        points_m, edges, spread = _edge_points(
            view, face, model, pose, plane_z_m, half_width_px, margin_px, near_outside_px
        )
        if len(points_m) < 3 * MIN_EDGE_POINTS or not _spans_two_directions(model, edges):
            return None, fits
        pose, residual = _gauss_newton(points_m, edges, model, pose, 0.05 * metre)
        excess = max(0.0, float(_median(spread)) - SHARP_EDGE_SPREAD)
        near_outside_px = 1.0 + 4.0 * excess
    rms_px = float(np.sqrt(np.mean(residual**2))) * px_per_m if len(residual) else math.inf
    yaw = fold_yaw(pose[2], model.symmetry_rad)
    fine = replace(best, x_m=pose[0], y_m=pose[1], yaw_rad=yaw, rms_px=rms_px, edge_points=len(residual))
    return fine, fits


def _corner_fit(view: _View, face: _Face, coarse: OutlineFit, plane_z_m: float, px_per_m: float) -> OutlineFit | None:
    """The outline's vertices by ``cv2.cornerSubPix`` on the face-coverage image, and a rigid fit of the model's."""
    model = coarse.model
    posed = model.posed(coarse.x_m, coarse.y_m, coarse.yaw_rad)
    start = _project(view, np.column_stack([posed, np.full(len(posed), plane_z_m)]))
    height, width = view.rgb.shape[:2]
    margin = 16
    x0, y0 = np.maximum(np.floor(start.min(axis=0)).astype(int) - margin, 0)
    x1, y1 = np.minimum(np.ceil(start.max(axis=0)).astype(int) + margin + 1, [width, height])
    face_chroma = face.face_chroma
    coverage = (chroma(view.rgb[y0:y1, x0:x1]) @ face_chroma / float(face_chroma @ face_chroma)).astype(np.float32)
    criteria = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_COUNT, 50, 1e-4)
    seeds = (start - [x0, y0]).astype(np.float32).reshape(-1, 1, 2)
    corners = cv2.cornerSubPix(coverage, seeds, (5, 5), (-1, -1), criteria).reshape(-1, 2).astype(float) + [x0, y0]
    if view.undistort is not None:
        corners = view.undistort(corners)
    measured = pixels_on_plane(view.intrinsics, view.T_W_C, corners, plane_z_m)
    # Procrustes: the rotation that best turns the model's vertices onto the measured ones.
    centre = measured.mean(axis=0)
    model_centre = model.outline_m.mean(axis=0)
    a, b = model.outline_m - model_centre, measured - centre
    yaw = math.atan2(float(np.sum(a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0])), float(np.sum(a * b)))
    c, s = math.cos(yaw), math.sin(yaw)
    origin = centre - np.array([[c, -s], [s, c]]) @ model_centre
    fitted = model.posed(float(origin[0]), float(origin[1]), yaw)
    rms_px = float(np.sqrt(np.mean(np.sum((fitted - measured) ** 2, axis=1)))) * px_per_m
    return replace(
        coarse,
        x_m=float(origin[0]),
        y_m=float(origin[1]),
        yaw_rad=fold_yaw(yaw, model.symmetry_rad),
        rms_px=rms_px,
        edge_points=len(measured),
    )


# -- outcomes ----------------------------------------------------------------------------------


@dataclass(frozen=True)
class _Verdict:
    """What one blob is: the model it fits (with the fit), or why it fits none."""

    blob_xy_m: tuple[float, float]
    fit: OutlineFit | None
    status: DetectionStatus
    reason: str
    area_px: float | None = None
    expected_area_px: float | None = None


def _judge(
    detector: CubeDetector,
    view: _View,
    colour: ColourRange,
    blob: Blob,
    blob_xy_m: tuple[float, float],
    models: Sequence[OutlineModel],
) -> dict[str, _Verdict]:
    """Register every known outline to one blob: what the blob is, for each model by name."""
    config = detector.config
    name = colour.name
    verdicts: dict[str, _Verdict] = {}
    faces: dict[float, _Face | None] = {}
    for model in models:
        plane_z_m = config.table_z_m + model.height_m
        if model.height_m not in faces:
            faces[model.height_m] = _face(detector, view, colour, blob, plane_z_m)
        face = faces[model.height_m]
        if face is None:
            verdicts[model.name] = _Verdict(
                blob_xy_m, None, DetectionStatus.PARTIAL, f"{name} blob vanished at full resolution"
            )
            continue
        if face.touches_border:
            verdicts[model.name] = _Verdict(
                blob_xy_m, None, DetectionStatus.PARTIAL, f"{name} face is cut by the image border", face.area_px
            )
            continue
        centre = np.array([face.centroid_m[0], face.centroid_m[1], plane_z_m])
        expected_px = replace(config, part=model.part).face_area_px(view.intrinsics, view.T_W_C, centre)
        px_per_m = math.sqrt(expected_px / model.area_m2)
        ratio = face.area_px / expected_px
        low, high = config.face_area_fraction_range
        if ratio > config.ambiguous_area_fraction:
            verdicts[model.name] = _Verdict(
                blob_xy_m,
                None,
                DetectionStatus.AMBIGUOUS,
                f"one {name} blob as large as {ratio:.1f} {model.name} faces: touching parts of one colour?",
                face.area_px,
                expected_px,
            )
        elif not low <= ratio <= high:
            verdicts[model.name] = _Verdict(
                blob_xy_m,
                None,
                DetectionStatus.PARTIAL,
                f"{name} blob is {ratio:.0%} of a {model.name} face: covered, or another part?",
                face.area_px,
                expected_px,
            )
        else:
            fine, fits = register(view, face, model, plane_z_m, px_per_m, config.kernel_px, config.corner_refinement)
            verdicts[model.name] = _verdict_of_fit(
                name, blob_xy_m, model, fine, fits, face.area_px, expected_px, config
            )
    return verdicts


def _verdict_of_fit(
    name: str,
    blob_xy_m: tuple[float, float],
    model: OutlineModel,
    fine: OutlineFit | None,
    fits: list[OutlineFit],
    area_px: float,
    expected_px: float,
    config: DetectorConfig,
) -> _Verdict:
    max_deviation_px = config.max_outline_deviation_px
    max_rms_px = config.max_reprojection_error_px
    if not fits:
        return _Verdict(blob_xy_m, None, DetectionStatus.PARTIAL, f"{name} face could not be registered", area_px)
    best = fits[0]
    if best.deviation_px > max_deviation_px:
        return _Verdict(
            blob_xy_m,
            best,
            DetectionStatus.WRONG_OUTLINE,
            f"{name} face is no {model.name} outline (strays {best.deviation_px:.1f} px from the best fit): "
            "another part, or covered?",
            area_px,
            expected_px,
        )
    if len(fits) > 1 and fits[1].deviation_px <= max_deviation_px:
        second = fits[1]
        return _Verdict(
            blob_xy_m,
            best,
            DetectionStatus.AMBIGUOUS,
            f"{name} {model.name} fits at yaw {math.degrees(best.yaw_rad):.1f} "
            f"and {math.degrees(second.yaw_rad):.1f} deg "
            f"(within {second.deviation_px:.1f} px): too nearly symmetric to tell apart at this resolution",
            area_px,
            expected_px,
        )
    if fine is None:
        return _Verdict(
            blob_xy_m,
            best,
            DetectionStatus.PARTIAL,
            f"{name} {model.name} edges could not be measured below a pixel",
            area_px,
            expected_px,
        )
    if fine.rms_px is None or fine.rms_px > max_rms_px:
        return _Verdict(
            blob_xy_m,
            fine,
            DetectionStatus.PARTIAL,
            f"{name} edges are not a {model.name} outline (residual {fine.rms_px:.2f} px)",
            area_px,
            expected_px,
        )
    return _Verdict(
        blob_xy_m,
        fine,
        DetectionStatus.FOUND,
        f"{name} {model.name} at x={fine.x_m:.4f} m, y={fine.y_m:.4f} m, yaw={math.degrees(fine.yaw_rad):.2f} deg",
        area_px,
        expected_px,
    )


def _detection(colour: str, verdict: _Verdict, xy: tuple[tuple[float, float], ...], table_z_m: float) -> Detection:
    fit = verdict.fit
    pose = None
    if verdict.status is DetectionStatus.FOUND and fit is not None:
        pose = Pose.from_planar(fit.x_m, fit.y_m, fit.yaw_rad, table_z_m + fit.model.height_m / 2)
    return Detection(
        colour,
        verdict.status,
        verdict.reason,
        pose_world=pose,
        reprojection_error_px=None if fit is None else fit.rms_px,
        area_px=verdict.area_px,
        expected_area_px=verdict.expected_area_px,
        candidates_xy_m=xy,
    )


def detect_outlines(
    detector: CubeDetector,
    view: _View,
    colour: ColourRange,
    roi: WorldRegion | None,
    models: Sequence[OutlineModel],
) -> dict[str, Detection]:
    """For each model (by name), the detection of the one part of ``colour`` with that outline."""
    name = colour.name
    candidates, outside_roi = detector._candidates(view, colour, roi)
    xy = tuple((float(p[0]), float(p[1])) for _, p, _ in candidates)
    if not candidates:
        where = "in the image" if roi is None else f"inside the region of interest ({outside_roi} outside)"
        reason = f"no {name} blob of at least {detector.config.min_area_fraction:.0%} of a face {where}"
        return {m.name: Detection(name, DetectionStatus.NOT_FOUND, reason) for m in models}
    judged: list[dict[str, _Verdict]] = []
    for blob, on_plane, _ in candidates:
        blob_xy = (float(on_plane[0]), float(on_plane[1]))
        try:
            judged.append(_judge(detector, view, colour, blob, blob_xy, models))
        except (cv2.error, ValueError, np.linalg.LinAlgError) as error:
            failed = _Verdict(
                blob_xy,
                None,
                DetectionStatus.PARTIAL,
                f"{name} face could not be measured: {type(error).__name__}: {error}",
            )
            judged.append({m.name: failed for m in models})
    # Each blob is the part whose outline it fits (the closest fit, if it fits several).
    owners: list[str | None] = []
    for verdicts in judged:
        fitting = [(v.fit.deviation_px, n) for n, v in verdicts.items() if v.status is DetectionStatus.FOUND and v.fit]
        owners.append(min(fitting)[1] if fitting else None)
    table_z_m = detector.config.table_z_m
    results: dict[str, Detection] = {}
    for model in models:
        mine = [verdicts[model.name] for verdicts, owner in zip(judged, owners, strict=True) if owner == model.name]
        rest = [verdicts[model.name] for verdicts, owner in zip(judged, owners, strict=True) if owner is None]
        if len(mine) == 1:
            results[model.name] = _detection(name, mine[0], xy, table_z_m)
        elif len(mine) > 1:
            where = ", ".join(f"({v.fit.x_m:.3f}, {v.fit.y_m:.3f})" for v in mine if v.fit is not None)
            results[model.name] = Detection(
                name,
                DetectionStatus.AMBIGUOUS,
                f"{len(mine)} {name} {model.name} faces, at {where} m; expected one",
                candidates_xy_m=xy,
            )
        elif len(rest) == 1:
            # One blob that could be this part (cut, covered, touching, no known outline): its outcome.
            results[model.name] = _detection(name, rest[0], xy, table_z_m)
        elif rest:
            reasons = "; ".join(v.reason for v in rest)
            results[model.name] = Detection(
                name,
                DetectionStatus.AMBIGUOUS,
                f"{len(rest)} {name} blobs, none a whole {model.name}: {reasons}",
                candidates_xy_m=xy,
            )
        else:
            others = ", ".join(
                f"the {owner} at ({v[owner].fit.x_m:.3f}, {v[owner].fit.y_m:.3f}) m"  # type: ignore[union-attr]
                for v, owner in zip(judged, owners, strict=True)
                if owner is not None
            )
            results[model.name] = Detection(
                name, DetectionStatus.WRONG_OUTLINE, f"no {name} {model.name} face, only {others}", candidates_xy_m=xy
            )
    return results


def detect_outline(detector: CubeDetector, view: _View, colour: ColourRange, roi: WorldRegion | None) -> Detection:
    """``CubeDetector``'s outcome for a prism part: the one part of ``colour`` whose face is its outline."""
    model = OutlineModel.of(detector.config.part)
    return detect_outlines(detector, view, colour, roi, [model])[model.name]


class OutlineDetector:
    """Finds prism parts' top faces by their outlines; parts of one colour are told apart by outline.

    ``detect(frame, colour, part=name)`` looks for one part (the first by default),
    ``detect_each(frame, colour)`` answers for every part by name: a face that fits another part's
    outline better is that part's. The blob search is the cube detector's.
    """

    def __init__(
        self,
        parts: Sequence[ObjectType],
        colours: ColourTable = DEFAULT_COLOUR_TABLE,
        config: DetectorConfig | None = None,
    ) -> None:
        if not parts:
            raise PerceptionError("an outline detector needs at least one part")
        self.models = tuple(OutlineModel.of(part) for part in parts)
        if len({m.name for m in self.models}) != len(self.models):
            raise PerceptionError(
                f"parts of an outline detector need distinct names, got {[m.name for m in self.models]}"
            )
        # The blob search keeps any blob of a quarter of the smallest face.
        smallest = min(self.models, key=lambda m: m.area_m2)
        self.search = CubeDetector(colours, replace(config or DetectorConfig(), part=smallest.part))

    def detect(
        self, frame: CameraFrame, colour: str, roi: WorldRegion | None = None, part: str | None = None
    ) -> Detection:
        """The part named ``part`` (default the first) of ``colour``."""
        results = self.detect_each(frame, colour, roi)
        name = part or self.models[0].name
        if name not in results:
            raise PerceptionError(f"unknown part {name!r}: this detector knows {', '.join(results)}")
        return results[name]

    def detect_each(self, frame: CameraFrame, colour: str, roi: WorldRegion | None = None) -> dict[str, Detection]:
        """Every part of ``colour`` by name, each told apart from the others by its outline."""
        colour_range = self.search.colours[colour]
        view = self.search._prepare(frame)
        return detect_outlines(self.search, view, colour_range, roi, self.models)
