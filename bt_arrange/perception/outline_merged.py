"""A part whose face merged with another of its colour: its known outline registered on its free edges.

Two parts of one colour closer than about a millimetre (two pixels at the top camera's 0.5 mm per
pixel, closed by the mask's 7x7 morphology) are one blob in the colour mask: a fresco piece
pushed past its place towards a neighbour. The blob is no outline the detector knows, so a
whole-face registration cannot say where the piece is, and its correction stops.

Where the part is expected to be (the region of interest's centre: its target when an Inspect
looks), its outline is registered into the blob instead:

1. **Coarse:** every yaw on a 2 degree grid with the centroid at the expected place, scored by
   the outline's samples' distance to the blob's contour (capped: the edges along the merged gap
   lie inside the blob, far from its contour); the best few yaws are refined by a trimmed
   point-to-line ICP on the contour points near the outline (a band shrinking from 4 mm to 1 px),
   so the neighbour's contour is never fitted.
2. **Free edges:** an edge of the fitted outline is free when the blob's contour follows it
   (80 % of its length within 1.5 px, its corners aside); the others face the neighbour across the
   merged gap. The whole outline must lie inside the blob, the free edges must hold half its
   perimeter and run in two directions 20 degrees apart or more, or the registration is refused.
3. **Sub-pixel:** the free edges alone are measured below a pixel and solved by trimmed least
   squares, exactly as a whole face's edges are (``bt_arrange.perception.outline.register``).

Nothing here is used for a blob that is one whole face; a blob two parts make is registered so
only from a region of interest.
"""

from __future__ import annotations

import math
from dataclasses import replace

import cv2
import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree

from bt_arrange.geometry import FloatArray, fold_yaw
from bt_arrange.perception.corners import SHARP_EDGE_SPREAD, _median
from bt_arrange.perception.outline_face import Face, edge_points, spans_two_directions
from bt_arrange.perception.outline_fit import (
    COARSE_POINTS,
    EDGE_PASSES,
    ICP_POINTS,
    MIN_EDGE_POINTS,
    OutlineFit,
    OutlineModel,
    _to_model,
    gauss_newton,
    resample,
    segment_distances,
)
from bt_arrange.perception.values import PreparedView

#: The coarse yaw grid (degrees) with the centroid at the expected place, and the score's cap (m).
MERGED_STEP_DEG = 2.0
MERGED_CAP_M = 0.004
#: The ICP's bands about the outline (m; the last is a pixel and a half), widest first.
MERGED_BANDS_M = (0.004, 0.002, 0.001)
#: An edge is free when this share of it (corners aside) lies within ``FREE_EDGE_PX`` of the contour.
FREE_EDGE_SHARE = 0.8
FREE_EDGE_PX = 1.5
#: The free edges must hold this share of the perimeter.
MIN_FREE_PERIMETER_SHARE = 0.5


def _outline_samples(model: OutlineModel, spacing_m: float, corner_m: float) -> tuple[FloatArray, FloatArray]:
    """Points along the outline (model frame) every ``spacing_m``, ``corner_m`` clear of each vertex; their edge."""
    points, edges = [], []
    for k in range(len(model.outline_m)):
        s = np.arange(
            min(corner_m, model.lengths[k] / 3), model.lengths[k] - min(corner_m, model.lengths[k] / 3), spacing_m
        )
        points.append(model.starts[k] + s[:, None] * model.directions[k])
        edges.append(np.full(len(s), k))
    return np.vstack(points), np.concatenate(edges)


def _nearest_m(points: FloatArray, contour: cKDTree, cap_m: float = math.inf) -> FloatArray:
    """Each point's distance to the nearest contour point (pixels about a pixel apart), at most ``cap_m``.

    A k-d tree of the contour answers in log time what a brute-force search answered in the
    contour's length (9.9 s of a 29 s fresco run; issue 36).
    """
    distances, _ = contour.query(points, distance_upper_bound=cap_m)
    return np.minimum(distances, cap_m)


def _posed(points: FloatArray, pose: tuple[float, float, float]) -> FloatArray:
    c, s = math.cos(pose[2]), math.sin(pose[2])
    return points @ np.array([[c, s], [-s, c]]) + np.array(pose[:2])


def _coarse(contour_m: FloatArray, model: OutlineModel, prior_xy_m: tuple[float, float]) -> list[float]:
    """Yaws on the grid, best first (local minima of the capped distance of the outline's samples to the contour)."""
    samples, _ = _outline_samples(model, 0.002, 0.0)
    contour = cKDTree(resample(contour_m, COARSE_POINTS * 2))
    turn = min(model.symmetry_rad, 2 * math.pi)
    count = max(1, int(round(math.degrees(turn) / MERGED_STEP_DEG)))
    yaws = np.arange(count) * (turn / count)
    scores = np.array(
        [np.mean(_nearest_m(_posed(samples, (*prior_xy_m, float(y))), contour, MERGED_CAP_M) ** 2) for y in yaws]
    )
    minima = [k for k in range(count) if scores[k] <= scores[k - 1] and scores[k] <= scores[(k + 1) % count]]
    return [float(yaws[k]) for k in sorted(minima, key=lambda k: scores[k])]


def _banded_icp(
    contour_m: FloatArray, model: OutlineModel, pose: tuple[float, float, float], px_m: float
) -> tuple[float, float, float]:
    """Point-to-line ICP on the contour points in a shrinking band about the posed outline (not the neighbour's)."""
    points = resample(contour_m, ICP_POINTS * 2) if len(contour_m) > ICP_POINTS * 2 else contour_m
    for band_m in (*MERGED_BANDS_M, FREE_EDGE_PX * px_m):
        for _ in range(4):
            local = _to_model(points, *pose)
            distances, t = segment_distances(local, model)
            edge = np.argmin(distances, axis=1)
            rows = np.arange(len(edge))
            near = (distances[rows, edge] <= band_m) & (t[rows, edge] > 0.0) & (t[rows, edge] < 1.0)
            if near.sum() < 6:
                return pose
            pose, _ = gauss_newton(points[near], edge[near], model, pose, 0.3 * px_m, iterations=3)
    return pose


def free_edges(
    contour_m: FloatArray, model: OutlineModel, pose: tuple[float, float, float], px_m: float
) -> NDArray[np.bool_] | None:
    """Which edges of the posed outline the contour follows; None when the outline does not lie inside the blob."""
    samples, edge_of = _outline_samples(model, 0.5 * px_m, 3.0 * px_m)
    world = _posed(samples, pose)
    on_contour = _nearest_m(world, cKDTree(contour_m)) <= FREE_EDGE_PX * px_m
    scale = 1.0 / px_m  # pointPolygonTest on a contour scaled to pixels on the plane
    polygon = (contour_m * scale).astype(np.float32).reshape(-1, 1, 2)
    inside = np.array([cv2.pointPolygonTest(polygon, (float(p[0]), float(p[1])), True) for p in world * scale])
    if np.any(inside < -FREE_EDGE_PX):
        return None  # part of the outline lies outside the blob: not this part, or not here
    share = np.array(
        [on_contour[edge_of == k].mean() if np.any(edge_of == k) else 0.0 for k in range(len(model.lengths))]
    )
    return share >= FREE_EDGE_SHARE


def register_in_merged(
    view: PreparedView,
    face: Face,
    model: OutlineModel,
    plane_z_m: float,
    px_per_m: float,
    prior_xy_m: tuple[float, float],
) -> OutlineFit | None:
    """The part's pose from its free edges in a blob merged with another part's face, or None (see the module)."""
    px_m = 1.0 / px_per_m
    best: tuple[float, tuple[float, float, float], np.ndarray] | None = None
    for yaw in _coarse(face.contour_m, model, prior_xy_m)[:3]:
        pose = _banded_icp(face.contour_m, model, (prior_xy_m[0], prior_xy_m[1], yaw), px_m)
        free = free_edges(face.contour_m, model, pose, px_m)
        if free is None or not free.any():
            continue
        share = float(model.lengths[free].sum() / model.lengths.sum())
        if best is None or share > best[0]:
            best = (share, pose, free)
    if best is None or best[0] < MIN_FREE_PERIMETER_SHARE:
        return None
    _, pose, free = best
    if not spans_two_directions(model, np.flatnonzero(free)):
        return None
    near_outside_px: float | None = None
    residual = np.empty(0)
    for half_width_px, margin_px in EDGE_PASSES:
        points_m, edges, spread = edge_points(
            view, face, model, pose, plane_z_m, half_width_px, margin_px, near_outside_px
        )
        keep = free[edges] if len(edges) else np.zeros(0, dtype=bool)
        points_m, edges, spread = points_m[keep], edges[keep], spread[keep]
        if len(points_m) < 3 * MIN_EDGE_POINTS or not spans_two_directions(model, edges):
            return None
        pose, residual = gauss_newton(points_m, edges, model, pose, 0.05 * px_m)
        near_outside_px = 1.0 + 4.0 * max(0.0, float(_median(spread)) - SHARP_EDGE_SPREAD)
    rms_px = float(np.sqrt(np.mean(residual**2))) * px_per_m if len(residual) else math.inf
    fit = OutlineFit(model, pose[0], pose[1], fold_yaw(pose[2], model.symmetry_rad), 0.0)
    return replace(fit, rms_px=rms_px, edge_points=len(residual))
