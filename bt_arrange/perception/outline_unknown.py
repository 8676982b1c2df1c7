"""Outlines of parts nobody described: each blob's top face measured as a polygon, below a pixel.

A fresco's pieces come out of the fracture convex, all of one colour, scattered at random; the
framework is told nothing of their outlines. :func:`measure_unknown_outlines` finds them from one
frame alone:

1. **The face** of each blob at full resolution (``outline_face.face_of``: the colour's mask cleaned
   by the 7x7 closing and opening, its Suzuki-Abe contour, the face's chroma). A blob cut by the image
   border is reported, and so is one that is not convex (two pieces touching, or under a millimetre
   apart where the image does not show their gap): its outline cannot be told from theirs.
2. **The polygon**: Douglas-Peucker on the contour (1.25 px), sides shorter than ``min_edge_m`` left
   out (the chamfers the morphology leaves at the corners), the contour's pixels of each remaining
   side fitted by a line (``cv2.fitLine``) and consecutive lines intersected: corners within about
   half a pixel, where the mask's rounded corners do not reach.
3. **Sub-pixel sides**: along each side the covered fractions of the pixels across the edge, unmixed
   in the chroma plane and summed (``corners._side_edge_points``, the box's edge measure), away from
   the corners and where no other side crosses the band (``clear_along_bands``); a band whose far
   end holds the colour (a neighbour under a few pixels away) is left out. The points are undistorted
   and taken onto the plane of the top faces (each pixel's ray meets ``z = plane_z_m``), a line is
   fitted per side there (total least squares, outliers trimmed), and consecutive lines meet at the
   vertices. Two passes, the second re-centred on the first's lines and reading the outside colour
   just beyond the measured edge spread.

Every step is vectorised over a side's pixels; the loops run over sides and blobs. The image knows
the vertices, never which piece is which: matching them to a fresco is the caller's.
:func:`measure_unknown_outlines_in_mask` does the same for a foreground mask (any pixel that is not
the table) for faces that carry a picture, where the face's colour is read per column just inside
the edge. Perception stays free of the simulator.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import cv2
import numpy as np
from numpy.typing import NDArray

from bt_arrange.geometry import FloatArray
from bt_arrange.perception.colours import ColourRange, Mask
from bt_arrange.perception.corners import INITIAL_OUTSIDE_PX, SHARP_EDGE_SPREAD, _median
from bt_arrange.perception.outline_face import face_of, project
from bt_arrange.perception.outline_fit import area_centroid, pixels_on_plane
from bt_arrange.perception.outline_unknown_edges import (
    MIN_SIDE_POINTS,
    Line,
    SideSampler,
    aliased_line,
    clear_along_bands,
    colour_sampler,
    edge_colours,
    fit_line,
    intersect,
    line_of_points,
    local_sampler,
)
from bt_arrange.perception.segmentation import Blob, clean_mask, find_blobs, to_hsv
from bt_arrange.perception.values import PreparedView
from bt_arrange.robot import CameraFrame

if TYPE_CHECKING:
    from bt_arrange.perception.detection import PartDetector

#: Douglas-Peucker's tolerance on the mask's contour (px).
POLYGON_TOLERANCE_PX = 1.25
#: A blob whose contour leaves its convex hull by more than this (px) is not one convex face.
MAX_CONCAVITY_PX = 2.5
#: The sub-pixel passes: (band half width, px; margin at the side's ends, px).
UNKNOWN_EDGE_PASSES: tuple[tuple[int, float], ...] = ((5, 2.0), (4, 2.0))
#: An edge point is kept this much (px) beyond its outside distance from every other side.
REACH_MARGIN_PX = 2.0
#: A sub-pixel vertex this far (px) from the pixel-level corner: a band fitted something else.
MAX_VERTEX_SHIFT_PX = 3.0
#: Two consecutive sides turning less than this are one side (Douglas-Peucker split it on noise).
MIN_TURN_DEG = 12.0
#: A short side (a few columns between its margins) is fitted to this many sub-pixel edge points at least.
MIN_SHORT_SIDE_POINTS = 4
#: Two pieces closer than this are "under a millimetre apart".
CLOSE_GAP_M = 0.001


@dataclass(frozen=True)
class MeasuredOutline:
    """One part's top face as the camera measured it, without a model.

    ``outline_m``: the vertices on the table (world x, y, metres), counter-clockwise seen from above,
    each where two fitted sides meet. ``plane_z_m``: the plane they were measured on (the top faces'
    height). ``edge_colours``: per edge (vertex k to k + 1) the face's RGB (0..1), sampled in order
    along it 1.5 px inside (a painted slab's colour-continuity cue across a fracture). ``residual_px``:
    the RMS distance of the sub-pixel edge points from their sides' lines.
    """

    outline_m: FloatArray
    plane_z_m: float
    edge_colours: tuple[FloatArray, ...]
    residual_px: float

    @property
    def centroid_m(self) -> FloatArray:
        """The area centroid of the outline (world x, y)."""
        return area_centroid(self.outline_m)[1]

    @property
    def area_m2(self) -> float:
        """The outline's area."""
        return area_centroid(self.outline_m)[0]


# -- a face's polygon ---------------------------------------------------------------------------


@dataclass(frozen=True)
class _Region:
    """One blob's face at full resolution: its contour (image px), the face's chroma (None: read per column)."""

    contour_px: NDArray[np.int32]
    face_chroma: FloatArray | None
    centre_m: FloatArray
    touches_border: bool
    #: The cleaned foreground mask, for a face read per column (``face_chroma`` None).
    foreground: Mask | None = None


def _concavity_px(contour: NDArray[np.int32]) -> float:
    """How deep (px) the contour leaves its convex hull at most."""
    points = contour.reshape(-1, 1, 2).astype(np.int32)
    if len(points) < 4:
        return 0.0
    hull = cv2.convexHull(points, returnPoints=False)
    try:
        defects = cv2.convexityDefects(points, np.sort(hull.ravel()).reshape(-1, 1))
    except cv2.error:  # a self-touching contour (a pixel-wide neck): no defects to read
        return math.inf
    if defects is None:
        return 0.0
    return float(np.asarray(defects).reshape(-1, 4)[:, 3].max()) / 256.0


def _pixel_polygon(contour: NDArray[np.int32], min_edge_px: float, kernel_px: int) -> FloatArray | None:
    """Corners within about half a pixel: the contour's side lines met.

    The sides are runs of the contour's Douglas-Peucker segments that turn less than ``MIN_TURN_DEG``
    from the run's longest; a short segment (under ``min_edge_px`` or the morphology's chamfer at a
    sharp corner, ``kernel_px + 2``) that turns more is no side: its neighbours' lines meet instead,
    where the contour must come within the rounding of a corner (``3 * kernel_px``). The contour runs
    through the outermost mask pixels, half a pixel inside the 50 % edge: each line is moved out by
    half a pixel. None when fewer than three sides remain or two meet far off the contour.
    """
    points = contour.reshape(-1, 2).astype(float)
    polygon = cv2.approxPolyDP(contour.reshape(-1, 1, 2), POLYGON_TOLERANCE_PX, True).reshape(-1, 2).astype(float)
    vectors = np.roll(polygon, -1, axis=0) - polygon
    lengths = np.hypot(*vectors.T)
    shortest = max(min_edge_px, kernel_px + 2.0)
    start = int(np.argmax(lengths))
    order = [(start + k) % len(polygon) for k in range(len(polygon))]
    limit = math.cos(math.radians(MIN_TURN_DEG))
    runs: list[list[int]] = []
    for k in order:
        direction = vectors[k] / max(lengths[k], 1e-9)
        if runs:
            leader = max(runs[-1], key=lambda i: lengths[i])
            if float(direction @ vectors[leader]) / lengths[leader] >= limit:
                runs[-1].append(k)
                continue
        if lengths[k] >= shortest:
            runs.append([k])
    if len(runs) > 1:  # the last run may continue the first
        first, last = runs[0], runs[-1]
        a, b = max(first, key=lambda i: lengths[i]), max(last, key=lambda i: lengths[i])
        if float(vectors[a] @ vectors[b]) / (lengths[a] * lengths[b]) >= limit:
            runs[0] = last + first
            runs.pop()
    if len(runs) < 3:
        return None
    centre = points.mean(axis=0)
    lines = []
    lengths_of_runs = []
    for run in runs:
        chosen = []
        for k in run:
            p = polygon[k]
            direction = vectors[k] / max(lengths[k], 1e-9)
            along = (points - p) @ direction
            across = (points - p) @ np.array([-direction[1], direction[0]])
            margin = min(3.0, 0.25 * lengths[k])
            chosen.append(points[(along > margin) & (along < lengths[k] - margin) & (np.abs(across) < 1.5)])
        side = np.vstack(chosen)
        if len(side) < 4:
            continue  # a chamfer of a few pixels: its neighbours meet instead
        point, direction = line_of_points(side)
        # Trim the pixels a rounded corner pulls off the line, once.
        residual = np.abs((side - point) @ np.array([-direction[1], direction[0]]))
        if int((residual < 1.0).sum()) >= 3:
            point, direction = line_of_points(side[residual < 1.0])
        outward = np.array([direction[1], -direction[0]])
        if outward @ (point - centre) < 0:
            outward = -outward
        lines.append((point + 0.5 * outward, direction))
        lengths_of_runs.append(float(sum(lengths[k] for k in run)))
    lines = _without_chamfers(lines, lengths_of_runs, 2.5 * kernel_px, kernel_px)
    if len(lines) < 3:
        return None
    corners = [intersect(lines[k - 1], lines[k]) for k in range(len(lines))]
    if any(c is None for c in corners):
        return None
    found = np.array(corners, dtype=float)
    # Each corner within a corner's rounding of the contour: else two sides met far off (a wrong side).
    off = np.hypot(*(found[:, None, :] - points[None, :, :]).transpose(2, 0, 1)).min(axis=1)
    if float(off.max()) > 3.0 * kernel_px:
        return None
    return found


def _chamfer_depth_px(before: FloatArray, after: FloatArray, kernel_px: int) -> float:
    """How far (px) a corner between sides along ``before`` and ``after`` may lie beyond the mask's rounding of it.

    The opening with a disc of radius ``r`` rounds a corner of interior angle ``b`` to an arc ``r / sin(b / 2) - r``
    inside it; a pixel and a half more for the contour's steps.
    """
    radius = kernel_px / 2
    turn = math.acos(float(np.clip(before @ after, -1.0, 1.0)))
    interior = max(math.pi - turn, math.radians(10.0))
    return radius / math.sin(interior / 2) - radius + 1.5


def _without_chamfers(lines: list[Line], lengths: list[float], short_px: float, kernel_px: int) -> list[Line]:
    """The lines without those of runs shorter than ``short_px`` whose neighbours meet near them.

    Such a run is the morphology's chamfer at a corner: the corner is where its neighbours meet, no
    farther beyond its line than the rounding reaches (``_chamfer_depth_px``). A short true side lies
    farther. Shortest first, never below three lines.
    """
    lines, lengths = list(lines), list(lengths)
    while len(lines) > 3:
        order = sorted(range(len(lines)), key=lambda k: lengths[k])
        for k in order:
            if lengths[k] >= short_px:
                return lines
            before, after = lines[k - 1], lines[(k + 1) % len(lines)]
            met = intersect(before, after)
            point, direction = lines[k]
            depth = _chamfer_depth_px(before[1], after[1], kernel_px)
            if met is not None and abs(float((met - point) @ np.array([-direction[1], direction[0]]))) <= depth:
                del lines[k], lengths[k]
                break
        else:
            return lines
    return lines


# -- sub-pixel sides ----------------------------------------------------------------------------


def _sub_pixel(
    view: PreparedView,
    corners_px: FloatArray,
    sampler: SideSampler,
    plane_z_m: float,
    px_per_m: float,
    short_px: float = 0.0,
) -> tuple[FloatArray, float, str | None, int | None]:
    """The vertices where the sub-pixel side lines meet (on the plane), the RMS residual (px); or why not, the side.

    A side shorter than ``short_px`` is fitted to ``MIN_SHORT_SIDE_POINTS`` edge points or more.
    """
    corners = corners_px
    count = len(corners)
    near_outside_px: float | None = None
    vertices = np.empty((0, 2))
    residuals: list[FloatArray] = []
    for half_width_px, margin_px in UNKNOWN_EDGE_PASSES:
        centre = corners.mean(axis=0)
        lines: list[Line] = []
        spreads, residuals = [], []
        for k in range(count):
            p, q = corners[k], corners[(k + 1) % count]
            points, spread = sampler(p, q, centre, half_width_px, margin_px, near_outside_px)
            if len(points):
                # The pixels a point's edge reads lie within its outside distance: clear of other sides.
                reach_px = (INITIAL_OUTSIDE_PX if near_outside_px is None else near_outside_px) + REACH_MARGIN_PX
                clear = clear_along_bands(points, corners, k, reach_px)
                points, spread = points[clear], spread[clear]
            needed = MIN_SHORT_SIDE_POINTS if float(np.hypot(*(q - p))) < short_px else MIN_SIDE_POINTS
            if len(points) < needed:
                return vertices, math.inf, f"side {k + 1} of {count} has {len(points)} edge points", k
            points = aliased_line(points, p, q)
            if view.undistort is not None:
                points = view.undistort(points)
            on_plane = pixels_on_plane(view.intrinsics, view.T_W_C, points, plane_z_m)
            line, residual = fit_line(on_plane, 0.05 / px_per_m)
            lines.append(line)
            residuals.append(residual)
            spreads.append(spread)
        found = [intersect(lines[k - 1], lines[k]) for k in range(count)]
        if any(v is None for v in found):
            return vertices, math.inf, "two consecutive sides are parallel", None
        vertices = np.array(found, dtype=float)
        corners = project(view, np.column_stack([vertices, np.full(count, plane_z_m)]))
        excess = max(0.0, float(_median(np.concatenate(spreads))) - SHARP_EDGE_SPREAD)
        near_outside_px = 1.0 + 4.0 * excess
    shift = float(np.max(np.hypot(*(corners - corners_px).T)))
    if shift > MAX_VERTEX_SHIFT_PX:
        return vertices, math.inf, f"a sub-pixel vertex moved {shift:.1f} px from the contour's corner", None
    every = np.concatenate(residuals) * px_per_m
    return vertices, float(np.sqrt(np.mean(every**2))), None, None


def _measure_sides(
    view: PreparedView,
    corners_px: FloatArray,
    sampler: SideSampler,
    plane_z_m: float,
    px_per_m: float,
    min_edge_m: float,
    kernel_px: int,
) -> tuple[FloatArray, float, str | None]:
    """``_sub_pixel``, a short side that cannot be fitted (or measures under ``min_edge_m``) left out.

    A side shorter than ``2.5 * kernel_px`` (a chamfer the morphology cut at a corner, or a side too
    short for the bands) whose edge cannot be measured is dropped: its neighbours meet instead, no
    farther beyond it than the morphology's rounding of the corner reaches (``_chamfer_depth_px``). A
    measured side under ``min_edge_m`` is dropped as long as its neighbours meet within that length of
    it. A longer side that cannot be measured is reported.
    """
    corners = corners_px
    min_edge_px = min_edge_m * px_per_m
    weak_px = max(min_edge_px, 2.5 * kernel_px)
    while True:
        slack_px = 0.0
        vertices, residual_px, why, side = _sub_pixel(view, corners, sampler, plane_z_m, px_per_m, weak_px)
        count = len(corners)
        if why is None:
            lengths = np.hypot(*(np.roll(vertices, -1, axis=0) - vertices).T)
            if count <= 3 or float(lengths.min()) >= min_edge_m:
                return vertices, residual_px, None
            side = int(np.argmin(lengths))
            corners = project(view, np.column_stack([vertices, np.full(count, plane_z_m)]))
            slack_px, why = min_edge_px, f"side {side + 1} of {count} is under {1000 * min_edge_m:g} mm"
        elif side is None or count <= 3:
            return vertices, residual_px, why
        length_px = float(np.hypot(*(corners[(side + 1) % count] - corners[side])))
        if length_px >= weak_px:
            return vertices, residual_px, why
        dropped = _without_side(corners, side, kernel_px, slack_px)
        if dropped is None:
            return vertices, residual_px, f"{why}; its neighbours meet far from it"
        corners = dropped


def _without_side(corners: FloatArray, side: int, kernel_px: int, slack_px: float) -> FloatArray | None:
    """The polygon with side ``side`` (corner ``side`` to ``side + 1``) left out: its neighbours' lines met.

    None when they meet farther beyond the side than a chamfer's depth (or ``slack_px``) allows.
    """
    count = len(corners)
    a, b, c, d = (corners[(side + offset) % count] for offset in (-1, 0, 1, 2))
    before = (a, (b - a) / max(float(np.hypot(*(b - a))), 1e-9))
    after = (c, (d - c) / max(float(np.hypot(*(d - c))), 1e-9))
    met = intersect(before, after)
    direction = (c - b) / max(float(np.hypot(*(c - b))), 1e-9)
    beyond = abs(float((met - b) @ np.array([-direction[1], direction[0]]))) if met is not None else math.inf
    if met is None or beyond > max(_chamfer_depth_px(before[1], after[1], kernel_px), slack_px):
        return None
    kept = [corners[k] for k in range(count) if k not in (side, (side + 1) % count)]
    kept.insert(side if side + 1 < count else 0, met)
    return np.array(kept, dtype=float)


# -- blobs to outlines --------------------------------------------------------------------------


def _mm(point: FloatArray) -> str:
    return f"({1000 * float(point[0]):.1f}, {1000 * float(point[1]):.1f}) mm"


def _view(detector: PartDetector, frame: CameraFrame | PreparedView) -> PreparedView:
    if isinstance(frame, PreparedView):
        return frame
    return detector._prepare(frame)  # noqa: SLF001  # the detector's one preparation of a frame


def _measure_region(
    view: PreparedView,
    region: _Region,
    plane_z_m: float,
    max_vertices: int,
    min_edge_m: float,
    name: str,
    kernel_px: int,
) -> tuple[MeasuredOutline | None, str | None]:
    """One face's outline, or why it has none (a line)."""
    where = _mm(region.centre_m)
    if region.touches_border:
        return None, f"a {name} blob at {where} is cut by the image border"
    concavity = _concavity_px(region.contour_px)
    if concavity > MAX_CONCAVITY_PX:
        return None, (
            f"a {name} blob at {where} is not convex (its outline leaves its hull by {concavity:.1f} px): pieces "
            "that touch or are under 1 mm apart, cannot tell their outlines apart"
        )
    contour_m = _contour_on_plane(view, region.contour_px, plane_z_m)
    area_m2, _ = area_centroid(contour_m)
    area_px = abs(float(cv2.contourArea(region.contour_px.reshape(-1, 1, 2))))
    if area_m2 <= 0 or area_px <= 0:
        return None, f"a {name} blob at {where} has no area on the plane"
    px_per_m = math.sqrt(area_px / area_m2)
    corners = _pixel_polygon(region.contour_px, min_edge_m * px_per_m, kernel_px)
    if corners is None:
        return None, f"a {name} blob at {where} has no polygon of 3 or more straight sides"
    if len(corners) > max_vertices:
        return None, f"a {name} blob at {where} has {len(corners)} sides, more than {max_vertices}: not one piece?"
    if region.face_chroma is None:
        assert region.foreground is not None
        sampler = local_sampler(view, region.foreground)
    else:
        sampler = colour_sampler(view, region.face_chroma)
    vertices, residual_px, why = _measure_sides(view, corners, sampler, plane_z_m, px_per_m, min_edge_m, kernel_px)
    if why is not None:
        return None, f"a {name} blob at {where}: its edges could not be measured below a pixel ({why})"
    if area_centroid_signed(vertices) < 0:
        vertices = vertices[::-1].copy()
    vertices_px = project(view, np.column_stack([vertices, np.full(len(vertices), plane_z_m)]))
    colours = edge_colours(view, vertices_px)
    return MeasuredOutline(vertices, plane_z_m, colours, residual_px), None


def area_centroid_signed(points: FloatArray) -> float:
    """A polygon's signed area (positive counter-clockwise)."""
    x, y = points[:, 0], points[:, 1]
    return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


def _contour_on_plane(view: PreparedView, contour_px: NDArray[np.int32], plane_z_m: float) -> FloatArray:
    points = contour_px.reshape(-1, 2).astype(float)
    if view.undistort is not None:
        points = view.undistort(points)
    return pixels_on_plane(view.intrinsics, view.T_W_C, points, plane_z_m)


def _close_pairs(view: PreparedView, regions: list[_Region], plane_z_m: float) -> set[tuple[int, int]]:
    """Pairs of regions whose faces come under ``CLOSE_GAP_M`` apart on the plane.

    The contours run half a pixel inside each face's edge: their distance less a pixel is the gap.
    """
    contours = [_contour_on_plane(view, r.contour_px, plane_z_m) for r in regions]
    pairs = set()
    for i in range(len(regions)):
        for j in range(i + 1, len(regions)):
            a, b = contours[i], contours[j]
            if not (np.all(np.isfinite(a)) and np.all(np.isfinite(b))):
                continue
            low = np.maximum(a.min(axis=0), b.min(axis=0))
            high = np.minimum(a.max(axis=0), b.max(axis=0))
            if np.any(low - high > 2 * CLOSE_GAP_M + 0.002):
                continue  # their boxes are far apart
            pixel_m = float(np.median(np.hypot(*np.diff(a, axis=0).T)))
            near_a = a[np.all((a >= low - 0.003) & (a <= high + 0.003), axis=1)]
            near_b = b[np.all((b >= low - 0.003) & (b <= high + 0.003), axis=1)]
            if len(near_a) == 0 or len(near_b) == 0:
                continue
            gaps = np.hypot(*(near_a[:, None, :] - near_b[None, :, :]).transpose(2, 0, 1))
            if float(gaps.min()) - pixel_m < CLOSE_GAP_M:
                pairs.add((i, j))
    return pairs


def _measure_regions(
    view: PreparedView,
    regions: list[_Region],
    plane_z_m: float,
    max_vertices: int,
    min_edge_m: float,
    name: str,
    kernel_px: int,
) -> tuple[list[MeasuredOutline], list[str]]:
    outcomes = [_measure_region(view, r, plane_z_m, max_vertices, min_edge_m, name, kernel_px) for r in regions]
    problems: list[str] = []
    close = _close_pairs(view, regions, plane_z_m)
    reported: set[int] = set()
    for i, j in sorted(close):
        # Told apart when both were measured; else the pair is the problem, not each blob's symptom.
        if outcomes[i][0] is not None and outcomes[j][0] is not None:
            continue
        problems.append(
            f"2 pieces of {name} at {_mm(regions[i].centre_m)} and {_mm(regions[j].centre_m)} touch or are under "
            "1 mm apart: cannot tell their outlines apart"
        )
        reported.update((i, j))
    outlines = []
    for k, (outline, problem) in enumerate(outcomes):
        if outline is not None:
            outlines.append(outline)
        elif problem is not None and k not in reported:
            problems.append(problem)
    return outlines, problems


def measure_unknown_outlines(
    detector: PartDetector,
    frame: CameraFrame | PreparedView,
    colour: str | ColourRange,
    plane_z_m: float,
    *,
    max_vertices: int = 16,
    min_edge_m: float = 0.003,
    painted: bool = False,
) -> tuple[list[MeasuredOutline], list[str]]:
    """Every whole face of ``colour`` measured as a convex polygon on ``z = plane_z_m``, and one line per problem.

    ``detector`` (a ``PartDetector``) gives the blob search and the cleaning; its part's size sets only
    the smallest blob looked at (a quarter of its face). ``frame`` is a camera frame or the detector's
    prepared view of one. Sides shorter than ``min_edge_m`` are left out (their neighbours meet
    instead); a face of more than ``max_vertices`` sides is reported, not measured. Outlines come back
    largest blob first. ``painted``: the faces carry a picture (``colour`` a range of many hues), so no
    one chroma is a face's colour at its edges: each side is measured against the face's colour read
    per column just inside it (:func:`measure_unknown_outlines_in_mask` on the colour's mask).
    """
    view = _view(detector, frame)
    colour_range = detector.colours[colour] if isinstance(colour, str) else colour
    if painted:
        mask = colour_range.mask(to_hsv(view.rgb))
        return measure_unknown_outlines_in_mask(
            detector, view, mask, plane_z_m, max_vertices=max_vertices, min_edge_m=min_edge_m, name=colour_range.name
        )
    candidates, _ = detector.candidates(view, colour_range, None)
    regions = []
    for blob, on_plane, _ in candidates:
        face = face_of(detector, view, colour_range, blob, plane_z_m)
        if face is None:
            continue
        regions.append(_Region(face.contour_px, face.face_chroma, np.asarray(on_plane[:2]), face.touches_border))
    kernel_px = detector.config.kernel_px
    return _measure_regions(view, regions, plane_z_m, max_vertices, min_edge_m, colour_range.name, kernel_px)


def measure_unknown_outlines_in_mask(
    detector: PartDetector,
    frame: CameraFrame | PreparedView,
    mask: Mask,
    plane_z_m: float,
    *,
    max_vertices: int = 16,
    min_edge_m: float = 0.003,
    name: str = "foreground",
) -> tuple[list[MeasuredOutline], list[str]]:
    """As :func:`measure_unknown_outlines` for the blobs of a foreground mask (uint8, nonzero: not the table).

    For faces that carry a picture, where no colour range holds a face: the mask is cleaned like a
    colour's, and each side's edge is measured against the face's colour read per column, just inside
    the edge (a picture of little chroma at the edge gives few points there).
    """
    view = _view(detector, frame)
    height, width = view.rgb.shape[:2]
    if mask.shape[:2] != (height, width):
        raise ValueError(f"the mask is {mask.shape[1]}x{mask.shape[0]} px, the image {width}x{height}")
    cleaned = clean_mask(np.where(mask > 0, 255, 0).astype(np.uint8), detector.config.kernel_px)
    regions = []
    for blob in find_blobs(cleaned, 1, view.min_blob_area_px):
        region = _mask_region(view, cleaned, blob, plane_z_m)
        if region is not None:
            regions.append(region)
    return _measure_regions(view, regions, plane_z_m, max_vertices, min_edge_m, name, detector.config.kernel_px)


def _mask_region(view: PreparedView, mask: Mask, blob: Blob, plane_z_m: float) -> _Region | None:
    height, width = mask.shape[:2]
    x, y, w, h = blob.bbox_px
    x0, y0, x1, y1 = max(0, x - 1), max(0, y - 1), min(width, x + w + 1), min(height, y + h + 1)
    contours, _ = cv2.findContours(mask[y0:y1, x0:x1], cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    if not contours:
        return None
    chosen = max(contours, key=cv2.contourArea)
    contour = chosen.reshape(-1, 2) + np.array([x0, y0])
    touches = bool(
        contour[:, 0].min() <= 0
        or contour[:, 1].min() <= 0
        or contour[:, 0].max() >= width - 1
        or contour[:, 1].max() >= height - 1
    )
    centre = pixels_on_plane(view.intrinsics, view.T_W_C, np.asarray([blob.centroid_px], dtype=float), plane_z_m)[0]
    return _Region(np.asarray(contour, dtype=np.int32), None, centre, touches, mask)
