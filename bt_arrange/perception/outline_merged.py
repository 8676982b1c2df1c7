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
from bt_arrange.perception.memo import Memo, array_key, model_key
from bt_arrange.perception.outline_face import Face, edge_points, face_share, project, spans_two_directions
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
    contour's length (9.9 s of a 29 s fresco run).
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
    # Every yaw's samples in one query of the tree (the same distances as a query a yaw).
    c, s = np.cos(yaws)[:, None], np.sin(yaws)[:, None]
    posed = np.stack(
        [samples[:, 0] * c - samples[:, 1] * s + prior_xy_m[0], samples[:, 0] * s + samples[:, 1] * c + prior_xy_m[1]],
        axis=-1,
    )
    nearest = _nearest_m(posed.reshape(-1, 2), contour, MERGED_CAP_M).reshape(count, len(samples))
    scores = np.mean(nearest**2, axis=1)
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
    to_contour_m = _nearest_m(world, cKDTree(contour_m))
    on_contour = to_contour_m <= FREE_EDGE_PX * px_m
    scale = 1.0 / px_m  # pointPolygonTest on a contour scaled to pixels on the plane
    polygon = (contour_m * scale).astype(np.float32).reshape(-1, 1, 2)
    # A sample within a pixel of a contour point is nearer the contour than FREE_EDGE_PX, inside
    # or out: only the others can lie that far outside the blob, and only they are tested.
    # The farthest from the contour first, the likeliest to lie outside: the first found ends the test.
    far_m = to_contour_m > px_m
    far = world[far_m][np.argsort(-to_contour_m[far_m], kind="stable")] * scale
    for p in far:
        if cv2.pointPolygonTest(polygon, (float(p[0]), float(p[1])), True) < -FREE_EDGE_PX:
            return None  # part of the outline lies outside the blob: not this part, or not here
    share = np.array(
        [on_contour[edge_of == k].mean() if np.any(edge_of == k) else 0.0 for k in range(len(model.lengths))]
    )
    return share >= FREE_EDGE_SHARE


#: The free edges' registrations of faces seen before (``bt_arrange.perception.memo``).
_FREE_POSES = Memo()


def _free_pose(
    contour_m: FloatArray, model: OutlineModel, prior_xy_m: tuple[float, float], px_m: float
) -> tuple[tuple[float, float, float], NDArray[np.bool_]] | None:
    """The outline's pose on the contour near the expected place and its free edges; None: refused.

    Steps 1 and 2 of the module's: on the contour alone, so kept across looks (``Memo``).
    """
    best: tuple[float, tuple[float, float, float], np.ndarray] | None = None
    for yaw in _coarse(contour_m, model, prior_xy_m)[:3]:
        pose = _banded_icp(contour_m, model, (prior_xy_m[0], prior_xy_m[1], yaw), px_m)
        free = free_edges(contour_m, model, pose, px_m)
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
    return pose, free


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
    key = (array_key(face.contour_m), model_key(model), prior_xy_m, px_m)
    found = _FREE_POSES.get(key, lambda: _free_pose(face.contour_m, model, prior_xy_m, px_m))
    if found is None:
        return None
    pose, free = found
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


# -- without an expected place -----------------------------------------------------------------

#: Yaws tried by the search for where in a merged blob a part lies (degrees apart), and how many
#: places it hands on to the registration above.
SEARCH_STEP_DEG = 3.0
SEARCH_CANDIDATES = 6
#: The search's raster (m a cell), and how far either side of an edge (m) it looks for the blob's inside.
SEARCH_CELL_M = 0.001
SEARCH_PROBE_M = 0.0015


def _outside(contour_m: FloatArray, margin_m: float) -> tuple[FloatArray, NDArray[np.float32]]:
    """The blob on a grid of ``SEARCH_CELL_M``: its origin, and 1 where a cell lies outside the blob."""
    origin = contour_m.min(axis=0) - margin_m
    size = np.ceil((contour_m.max(axis=0) + margin_m - origin) / SEARCH_CELL_M).astype(int) + 1
    cells = np.round((contour_m - origin) / SEARCH_CELL_M).astype(np.int32).reshape(-1, 1, 2)
    outside = np.ones((size[1], size[0]), np.float32)
    cv2.fillPoly(outside, [cells], 0.0)
    return origin, outside


def _probe_template(points: FloatArray, half: int) -> NDArray[np.float32]:
    template = np.zeros((2 * half + 1, 2 * half + 1), np.float32)
    cells = np.round(points / SEARCH_CELL_M).astype(int) + half
    np.add.at(template, (cells[:, 1], cells[:, 0]), 1.0)
    return template


def places_in_merged(contour_m: FloatArray, model: OutlineModel) -> list[tuple[float, float]]:
    """Where in a merged blob the part may lie (its centroid, best first), found without an expected place.

    Each edge of the outline is probed ``SEARCH_PROBE_M`` either side: a free edge has the blob's
    outside just beyond it, and no edge may have it just within. The outline, turned to every
    ``SEARCH_STEP_DEG``, is slid over the blob by ``cv2.matchTemplate`` and each place scored by
    the share of outer probes outside the blob, less four times the share of inner probes outside.
    The best few places, half a part's size apart, go on to ``register_in_merged`` as expected places.
    """
    reach_m = float(np.max(np.hypot(*model.outline_m.T)))
    origin, outside = _outside(contour_m, reach_m + 2 * SEARCH_PROBE_M + 2 * SEARCH_CELL_M)
    samples, edge_of = _outline_samples(model, SEARCH_CELL_M, 2 * SEARCH_PROBE_M)
    normals = model.normals[edge_of]
    half = int(np.ceil((reach_m + SEARCH_PROBE_M) / SEARCH_CELL_M)) + 1
    if 2 * half + 1 > min(outside.shape):
        return []
    scored: list[tuple[float, float, float]] = []
    for yaw in np.radians(np.arange(0.0, 360.0, SEARCH_STEP_DEG)):
        pose = (0.0, 0.0, float(yaw))
        outer = _probe_template(_posed(samples + SEARCH_PROBE_M * normals, pose), half)
        inner = _probe_template(_posed(samples - SEARCH_PROBE_M * normals, pose), half)
        # Lower is better: minus the outer probes outside the blob, plus four for each inner one outside
        # (one correlation: it is linear in the template).
        score = cv2.matchTemplate(outside, 4.0 * inner - outer, cv2.TM_CCORR) / len(samples)
        apart = max(2, int(0.5 * reach_m / SEARCH_CELL_M))
        for _ in range(SEARCH_CANDIDATES):
            row, column = np.unravel_index(int(np.argmin(score)), score.shape)
            scored.append(
                (
                    float(score[row, column]),
                    float(origin[0] + (column + half) * SEARCH_CELL_M),
                    float(origin[1] + (row + half) * SEARCH_CELL_M),
                )
            )
            score[max(0, row - apart) : row + apart + 1, max(0, column - apart) : column + apart + 1] = np.inf
    places: list[tuple[float, float]] = []
    for _, x, y in sorted(scored):
        if all(math.hypot(x - px, y - py) > 0.5 * reach_m for px, py in places):
            places.append((x, y))
        if len(places) == SEARCH_CANDIDATES:
            break
    return places


#: Two fits in one blob this far apart (m, or degrees of yaw) are two places the part could be.
SAME_PLACE_M = 0.002
SAME_PLACE_DEG = 2.0
#: A fit's edges that face a neighbour must run along a seam: the face's colour at most this strong
#: (its share of the face's chroma, least within a pixel outside the edge) on average along them.
MAX_SEAM_COVERAGE = 0.8


def seam_coverage(
    view: PreparedView, face: Face, model: OutlineModel, fit: OutlineFit, plane_z_m: float, px_per_m: float
) -> float:
    """How much of the face's colour lies just outside the fit's edges that face a neighbour (0 a gap, 1 none).

    Inside a blob two faces make, the edges that face the neighbour run along the gap between them:
    narrower than the mask's morphology, it still shows in the image as pixels only partly the
    face's colour. Where a wrong place put the outline, those edges cross the middle of a face.
    Sampled every pixel along those edges, a half and one pixel outside them, the least of the
    two; 0 when every edge is free.
    """
    px_m = 1.0 / px_per_m
    pose = (fit.x_m, fit.y_m, fit.yaw_rad)
    free = free_edges(face.contour_m, model, pose, px_m)
    if free is None:
        return 1.0
    samples, edge_of = _outline_samples(model, px_m, 3.0 * px_m)
    facing = ~free[edge_of]
    if not facing.any():
        return 0.0
    samples, normals = samples[facing], model.normals[edge_of[facing]]
    height, width = view.rgb.shape[:2]
    least = np.full(len(samples), np.inf)
    for offset_px in (0.5, 1.0):
        world = _posed(samples + offset_px * px_m * normals, pose)
        pixels = np.round(project(view, np.column_stack([world, np.full(len(world), plane_z_m)]))).astype(int)
        u, v = np.clip(pixels[:, 0], 0, width - 1), np.clip(pixels[:, 1], 0, height - 1)
        least = np.minimum(least, face_share(face, view.rgb[v, u]))
    return float(np.mean(np.clip(least, 0.0, 1.0)))


def find_in_merged(
    view: PreparedView, face: Face, model: OutlineModel, plane_z_m: float, px_per_m: float, max_rms_px: float
) -> tuple[OutlineFit | None, int]:
    """The part's pose in a blob merged with others of its colour, with no expected place (Detect before picking).

    Every place ``places_in_merged`` finds is registered on its free edges as if the part were
    expected there (``register_in_merged``), and kept when its residual is under ``max_rms_px``
    and its other edges run along a seam (``seam_coverage``). Returns the fit and how many
    different places fit: the fit only when exactly one does, else None (two places are no answer).
    """
    fits: list[OutlineFit] = []
    for place in places_in_merged(face.contour_m, model):
        fit = register_in_merged(view, face, model, plane_z_m, px_per_m, place)
        if fit is None or fit.rms_px is None or fit.rms_px > max_rms_px:
            continue
        if any(
            math.hypot(fit.x_m - other.x_m, fit.y_m - other.y_m) < SAME_PLACE_M
            and abs(math.degrees(fold_yaw(fit.yaw_rad - other.yaw_rad, model.symmetry_rad))) < SAME_PLACE_DEG
            for other in fits
        ):
            continue
        if seam_coverage(view, face, model, fit, plane_z_m, px_per_m) <= MAX_SEAM_COVERAGE:
            fits.append(fit)
    return (fits[0] if len(fits) == 1 else None), len(fits)
