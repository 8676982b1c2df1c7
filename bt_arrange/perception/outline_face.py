"""A flat part's face in the image and the sub-pixel points on its model's edges.

The lowest room of the outline side: :func:`face_of` finds a blob's face at full resolution (its
contour taken onto the plane of the top faces, its chroma), :func:`edge_points` measures the
model's edges at a pose below a pixel (``bt_arrange.perception.corners``), and
:func:`spans_two_directions` says whether measured edges fix x, y and yaw. Both the single face's
registration (``outline``) and a face merged with a neighbour's (``outline_merged``) use them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol

import cv2
import numpy as np
from numpy.typing import NDArray

from bt_arrange.geometry import FloatArray
from bt_arrange.perception.colours import ColourRange
from bt_arrange.perception.corners import INITIAL_OUTSIDE_PX, _local_side_points, _median, _side_edge_points, chroma
from bt_arrange.perception.outline_fit import (
    MIN_EDGE_POINTS,
    EdgeSegments,
    OutlineModel,
    area_centroid,
    pixels_on_plane,
    segment_distances,
)
from bt_arrange.perception.segmentation import Blob, colour_mask, to_hsv
from bt_arrange.perception.values import DetectorConfig, PreparedView, WorldRegion


class FaceSearch(Protocol):
    """What the outline side needs of a detector (``PartDetector`` is one): its config and its blob search."""

    config: DetectorConfig

    def candidates(
        self, view: PreparedView, colour: ColourRange, roi: WorldRegion | None
    ) -> tuple[list[tuple[Blob, FloatArray, float]], int]:
        """Blobs of the colour that may be faces (blob, centre on the plane, area px), and how many lay outside."""
        ...


@dataclass(frozen=True)
class Face:
    """One blob's face at full resolution: contour (image px), its area, on the plane, the face's chroma.

    ``picture_colour``: a painted face's colour (a range of many hues, ``ColourRange.many_hues``). Its
    edges are measured against its colour read per column just inside them, and the range tells
    what lies beyond one (``face_share``); None: the face is of one chroma.
    """

    contour_px: NDArray[np.int32]
    area_px: float
    contour_m: FloatArray
    area_m2: float
    centroid_m: FloatArray
    face_chroma: FloatArray
    touches_border: bool
    picture_colour: ColourRange | None = None


def face_of(detector: FaceSearch, view: PreparedView, colour: ColourRange, blob: Blob, plane_z_m: float) -> Face | None:
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
    area_m2, centroid = area_centroid(on_plane)
    inner = np.zeros_like(mask)
    cv2.drawContours(inner, [chosen], -1, 255, thickness=cv2.FILLED)
    inner = np.asarray(cv2.erode(inner & mask, np.ones((5, 5), np.uint8)), dtype=np.uint8)
    v, u = np.nonzero(inner)
    if len(u) == 0:
        return None
    take = np.linspace(0, len(u) - 1, min(len(u), 400)).astype(int)
    face = _median(chroma(view.rgb[v[take] + y0, u[take] + x0]), axis=0)
    return Face(contour, area_px, on_plane, area_m2, centroid, face, touches, colour if colour.many_hues else None)


def face_share(face: Face, pixels_rgb: NDArray[np.uint8]) -> FloatArray:
    """How much of each pixel (N x 3 RGB) is the face's: its chroma's share of the face's; 1 or 0 by a painted range."""
    if face.picture_colour is not None:
        if len(pixels_rgb) == 0:
            return np.empty(0)
        hsv = to_hsv(np.ascontiguousarray(pixels_rgb, dtype=np.uint8).reshape(-1, 1, 3))
        return (face.picture_colour.mask(hsv).reshape(-1) > 0).astype(float)
    return np.asarray(chroma(pixels_rgb) @ face.face_chroma / float(face.face_chroma @ face.face_chroma))


def project(view: PreparedView, points_world: FloatArray) -> FloatArray:
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


def edge_points(
    view: PreparedView,
    face: Face,
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
    corners_px = project(view, np.hstack([posed, z]))
    # A point just inside each edge's middle tells the edge sampler which side the face is.
    middles = (posed + np.roll(posed, -1, axis=0)) / 2
    c, s = math.cos(pose[2]), math.sin(pose[2])
    world_normals = model.normals @ np.array([[c, s], [-s, c]])
    inside_px = project(view, np.hstack([middles - 0.002 * world_normals, z]))
    image_edges = EdgeSegments.closed(corners_px)
    all_points, all_edges, spreads = [], [], []
    for k in range(count):
        p, q = corners_px[k], corners_px[(k + 1) % count]
        if face.picture_colour is None:
            points, spread = _side_edge_points(
                view.rgb, p, q, inside_px[k], face.face_chroma, half_width_px, margin_px, near_outside_px
            )
        else:  # painted: no one chroma is the face's at its edges
            points, spread = _local_side_points(view.rgb, p, q, inside_px[k], half_width_px, margin_px, near_outside_px)
        if len(points) == 0:
            continue
        # Keep the points whose band cannot reach another edge of the face.
        distances, _ = segment_distances(points, image_edges)
        distances[:, k] = np.inf
        clear = distances.min(axis=1) >= half_width_px + 2.0
        points, spread = points[clear], spread[clear]
        # And those whose outside, where the sampler reads it (``near_outside_px`` beyond the edge, then
        # a pixel), is not the face's colour: a neighbour of the colour a pixel or two across the edge
        # (a sub-millimetre gap) puts its own face there, and the fit off it. A neighbour farther
        # (2 mm is 4 px) lies beyond what the sampler reads: its edges are measured as a free part's.
        reach_px = (INITIAL_OUTSIDE_PX if near_outside_px is None else near_outside_px) + 1.0
        beyond = _outward_pixels(view.rgb, points, p, q, inside_px[k], min(reach_px, half_width_px + 1.0))
        free = face_share(face, beyond) <= OUTSIDE_MAX_COVERAGE
        points, spread = points[free], spread[free]
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


#: Beyond an edge, the face's colour at most this strong (its share of the face's chroma): the outside.
OUTSIDE_MAX_COVERAGE = 0.5


def _outside_is_clear(
    rgb: NDArray[np.uint8],
    points_px: FloatArray,
    p: FloatArray,
    q: FloatArray,
    inside_px: FloatArray,
    face_chroma: FloatArray,
    reach_px: float,
) -> NDArray[np.bool_]:
    """Which edge points (image px) have no face of the colour ``reach_px`` beyond them, outward."""
    beyond = _outward_pixels(rgb, points_px, p, q, inside_px, reach_px)
    coverage = chroma(beyond) @ face_chroma / float(face_chroma @ face_chroma)
    return np.asarray(coverage <= OUTSIDE_MAX_COVERAGE)


def _outward_pixels(
    rgb: NDArray[np.uint8], points_px: FloatArray, p: FloatArray, q: FloatArray, inside_px: FloatArray, reach_px: float
) -> NDArray[np.uint8]:
    """The pixels (N x 3 RGB) ``reach_px`` beyond edge points of the side ``p`` to ``q``, away from ``inside_px``."""
    along = (q - p) / max(float(np.hypot(*(q - p))), 1e-9)
    normal = np.array([along[1], -along[0]])
    if float(normal @ (inside_px - (p + q) / 2)) > 0:
        normal = -normal  # outward: away from the point inside the face
    probes = np.round(points_px + reach_px * normal).astype(int)
    height, width = rgb.shape[:2]
    u, v = np.clip(probes[:, 0], 0, width - 1), np.clip(probes[:, 1], 0, height - 1)
    return np.asarray(rgb[v, u], dtype=np.uint8)


def spans_two_directions(model: OutlineModel, edges: NDArray[np.intp]) -> bool:
    """True when the measured edges hold two directions at least 20 degrees apart (x, y and yaw are then fixed)."""
    used = np.unique(edges)
    if len(used) < 2:
        return False
    normals = model.normals[used]
    return float(np.min(np.abs(normals @ normals.T))) < math.cos(math.radians(20.0))
