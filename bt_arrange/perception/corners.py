"""Sub-pixel corners of a top face.

At 1920x1080 and 70 cm one pixel covers about 0.5 mm of the table and the arrangement
threshold is 1 mm, so the Douglas-Peucker vertices (whole pixels, and rounded off by the 7x7
morphology at the corners) are not good enough. Lines fitted to the contour's pixels of each
side (``cv2.fitLine``) bring the corners within about half a pixel; from there the default,
:attr:`CornerRefinement.EDGE_LINES`, measures each side's edge below a pixel and intersects the
four fitted lines:

* A camera integrates light over each pixel, so an edge pixel's colour is a mix
  ``c * face + (1 - c) * outside`` where ``c`` is the fraction of the pixel the face covers.
  The mix is linear in RGB; solving it for ``c`` in the chroma plane (RGB minus its grey part)
  makes any grey neighbour (the table, the white part sides, the robot) count as "outside"
  whatever its brightness, and a coloured neighbour is unmixed with its own colour (each pixel
  from that colour or from grey, whichever mix lies nearer it: a grey side strip between the
  face and a coloured face beyond is outside too; ``_covered``).
* Summed over a column of pixels that crosses an edge, the covered fractions give the edge's
  height at the column's centre exactly, whatever the slope (the area under a straight line
  over a unit-wide column is its value at the centre). Sides closer to vertical use rows.
* The outside colour is read per column, just beyond the edge's spread (1 px for a sharp
  edge, more when blurred, measured from the face's own edges): a neighbour changes along a
  side (the table, then a touching part), and a part's side seen as a strip of a pixel or two
  must count as outside even though it is a slightly different grey than the table beyond.
  Pixels as far inside count as exactly 1, which keeps their noise out of the sum.
* A least-squares line through these points per side, with outliers trimmed, and the corners
  where adjacent lines meet: the rounded corners of the mask never enter.

``CORNER_SUBPIX`` (``cv2.cornerSubPix`` on the face-coverage image), ``CONTOUR_LINES`` (the
pixel-level lines alone) and ``NONE`` (the polygon's vertices) remain for comparison; see
docs/perception.md for the measured accuracy of each.
"""

from __future__ import annotations

import enum
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray

from bt_arrange.geometry import FloatArray

#: Points (Nx2, pixels) -> undistorted points (Nx2, pixels), for a lens with distortion.
Undistort = Callable[[FloatArray], FloatArray]

_SQRT2 = np.sqrt(2.0)
_SQRT6 = np.sqrt(6.0)


class CornerRefinement(str, enum.Enum):
    """How to bring the four corners below a pixel."""

    EDGE_LINES = "edge_lines"
    CORNER_SUBPIX = "corner_subpix"
    CONTOUR_LINES = "contour_lines"
    NONE = "none"


def chroma(rgb: NDArray[np.floating] | NDArray[np.uint8]) -> FloatArray:
    """The chroma plane of RGB (..., 3) -> (..., 2): an orthonormal basis orthogonal to grey.

    Linear, so an anti-aliased mix of two colours stays the same mix of their chromas, and
    every grey, light or dark, maps to about zero.
    """
    x = np.asarray(rgb, dtype=np.float64)
    r, g, b = x[..., 0], x[..., 1], x[..., 2]
    return np.stack([(r - g) / _SQRT2, (r + g - 2.0 * b) / _SQRT6], axis=-1)


def face_chroma(rgb: NDArray[np.uint8], corners_px: FloatArray) -> FloatArray:
    """Median chroma of the face, sampled on a grid well inside its four corners."""
    s = np.linspace(0.2, 0.8, 9)
    a, b = np.meshgrid(s, s)
    a, b = a.ravel()[:, None], b.ravel()[:, None]
    p0, p1, p2, p3 = corners_px
    points = (1 - a) * (1 - b) * p0 + a * (1 - b) * p1 + a * b * p2 + (1 - a) * b * p3
    height, width = rgb.shape[:2]
    u = np.clip(np.round(points[:, 0]).astype(int), 0, width - 1)
    v = np.clip(np.round(points[:, 1]).astype(int), 0, height - 1)
    return _median(chroma(rgb[v, u]), axis=0)


def _median(values: FloatArray, axis: int | None = None) -> FloatArray:
    """``np.median``, the same values, without numpy's lazy import of ``numpy.ma`` on its first call.

    That import is most of the first detection's time in a process (about 8 ms of CPU).
    """
    ordered = np.sort(np.asarray(values, dtype=np.float64), axis=axis)
    if axis is None:
        ordered = ordered.reshape(-1)
        axis = 0
    count = ordered.shape[axis]
    middle = np.take(ordered, [(count - 1) // 2, count // 2], axis=axis)
    median = np.mean(middle, axis=axis)  # np.median averages the two middle values the same way
    last = np.take(ordered, count - 1, axis=axis)
    # A NaN sorts last and makes np.median NaN.
    return np.asarray(np.where(np.isnan(last), np.nan, median), dtype=np.float64)


def _cross(a: Sequence[float] | FloatArray, b: Sequence[float] | FloatArray) -> FloatArray:
    """``np.cross`` of two 3-vectors, the same arithmetic without its axis handling (a tenth of the time)."""
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


def _line_through(p: FloatArray, q: FloatArray) -> FloatArray:
    """Homogeneous line ``(a, b, c)``, ``a u + b v + c = 0``, through two points."""
    return _cross([p[0], p[1], 1.0], [q[0], q[1], 1.0])


def _intersect(line_a: FloatArray, line_b: FloatArray) -> FloatArray:
    point = _cross(line_a, line_b)
    return point[:2] / point[2]


def _intersect_sides(lines: list[FloatArray]) -> FloatArray:
    """Corner ``i`` is where side ``i - 1`` (into it) meets side ``i`` (out of it)."""
    return np.array([_intersect(lines[i - 1], lines[i]) for i in range(4)])


#: The spread (summed min(c, 1 - c) across an edge) of an area-sampled edge without blur.
SHARP_EDGE_SPREAD = 0.25
#: The first pass reads the outside colour this far beyond the starting line (pixels): the
#: starting corners are within a pixel, a sharp edge mixes one more.
INITIAL_OUTSIDE_PX = 2.0


#: A pixel's unmixed coverage this far below none or above all (a fraction of the pixel) is no
#: mix of the face and the outside read (camera noise moves it a few hundredths): set to none or all.
GROSS_COVERAGE = 0.25
#: An outside colour counts as coloured (a neighbour's face, not the table or a part's side) when its
#: chroma is at least this fraction of the face's (the simulator's table: 0.03 of a face's).
COLOURED_OUTSIDE = 0.3


def _unmixed(x: FloatArray, face: FloatArray, outside: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Each pixel's (columns, band) face fraction unmixed from ``outside`` (columns, 2), and its distance off it."""
    contrast = face[None, :] - outside
    contrast_sq = np.maximum(np.einsum("ij,ij->i", contrast, contrast), 1e-12)
    c = np.einsum("ijk,ik->ij", x - outside[:, None, :], contrast) / contrast_sq[:, None]
    mixed = outside[:, None, :] + c[..., None] * contrast[:, None, :]
    return c, np.linalg.norm(x - mixed, axis=-1)


def _covered(x: FloatArray, face: FloatArray, outside: FloatArray) -> FloatArray:
    """Fraction of each pixel (columns, band) covered by the face, unmixed from ``outside`` or from grey.

    Each pixel is taken as the mix that explains it better: the face with the column's outside
    colour, or the face with grey (a part's side, the table; chroma zero). A raised part's side
    seen as a grey strip between its face and a coloured face below (a pallet's upper bar over
    the red layer) is no mix of blue and red: unmixed from red, each of its pixels counted half
    the face, and the edge came out a pixel too far (0.23 mm on the pallet's bars).

    Only beside a coloured outside (chroma at least ``COLOURED_OUTSIDE`` of the face's): beside
    the table, itself a grey, the choice would only follow the camera noise.
    """
    c_outside, off_outside = _unmixed(x, face, outside)
    c_grey, off_grey = _unmixed(x, face, np.zeros_like(outside))
    coloured = np.linalg.norm(outside, axis=-1) >= COLOURED_OUTSIDE * float(np.linalg.norm(face))
    return np.where(coloured[:, None] & (off_grey < off_outside), c_grey, c_outside)


@dataclass(frozen=True)
class _EdgeBand:
    """The pixels across one side, a column each (rows for a side nearer vertical: a transposed view).

    ``x`` is their chroma (columns, band, 2), index 0 at the face's end of the band, growing
    outwards; ``line_position`` is where the side's line crosses each column, counted the same way.
    """

    x: FloatArray
    u: NDArray[np.int_]
    v_line: FloatArray
    v_start: NDArray[np.int_]
    half_width_px: int
    face_above: bool
    by_columns: bool

    @property
    def line_position(self) -> FloatArray:
        """The side's line in each column, in pixels from the face's end of the band."""
        if self.face_above:
            return self.v_line - self.v_start + 0.5
        return self.v_start + 2 * self.half_width_px + 0.5 - self.v_line

    def v_edge(self, edge: FloatArray) -> FloatArray:
        """An edge ``edge`` pixels from the face's end of each column, as image v (u in the transposed view)."""
        if self.face_above:
            return self.v_start - 0.5 + edge
        return self.v_start + 2 * self.half_width_px + 0.5 - edge

    def points(self, v_edge: FloatArray, good: NDArray[np.bool_]) -> FloatArray:
        """The ``good`` columns' edge points as image (u, v)."""
        points = np.column_stack([self.u[good].astype(float), v_edge[good]])
        return points if self.by_columns else points[:, ::-1]


def _edge_band(
    rgb: NDArray[np.uint8], p: FloatArray, q: FloatArray, face_centre: FloatArray, half_width_px: int, margin_px: float
) -> _EdgeBand | None:
    """The band of pixels across the side from ``p`` to ``q``, or None when under 3 columns lie in the image."""
    direction = q - p
    by_columns = abs(direction[0]) >= abs(direction[1])
    if not by_columns:
        rgb = rgb.transpose(1, 0, 2)
        p, q, face_centre, direction = p[::-1], q[::-1], face_centre[::-1], direction[::-1]
    height, width = rgb.shape[:2]
    length_px = float(np.hypot(*direction))
    slope = direction[1] / direction[0]
    # Skip the ends of the side, where the band of pixels would also cross the adjacent sides.
    margin_u = margin_px * abs(direction[0]) / length_px
    u_low, u_high = sorted((p[0], q[0]))
    u = np.arange(np.ceil(u_low + margin_u), np.floor(u_high - margin_u) + 1).astype(int)
    if len(u) < 3:
        return None
    v_line = p[1] + (u - p[0]) * slope
    face_above = bool((face_centre[1] - (p[1] + (face_centre[0] - p[0]) * slope)) < 0)
    v_start = np.round(v_line).astype(int) - half_width_px
    rows = v_start[:, None] + np.arange(2 * half_width_px + 1)[None, :]
    keep = (u >= 0) & (u < width) & (rows[:, 0] >= 0) & (rows[:, -1] < height)
    u, v_line, v_start, rows = u[keep], v_line[keep], v_start[keep], rows[keep]
    if len(u) < 3:
        return None
    x = chroma(rgb[rows, u[:, None]])  # (columns, band, 2)
    if not face_above:
        x = x[:, ::-1]
    return _EdgeBand(x, u, v_line, v_start, half_width_px, face_above, by_columns)


def _side_edge_points(
    rgb: NDArray[np.uint8],
    p: FloatArray,
    q: FloatArray,
    face_centre: FloatArray,
    face: FloatArray,
    half_width_px: int,
    margin_px: float,
    near_outside_px: float | None,
) -> tuple[FloatArray, FloatArray]:
    """Sub-pixel points on the edge between corners ``p`` and ``q`` (Nx2), from pixel coverages.

    Each column's outside colour comes from the band's far end, or, with ``near_outside_px``,
    from the first pixel whose centre lies that far beyond the edge. Also returns each column's
    spread: the summed ``min(c, 1 - c)`` of its covered fractions ``c``, about 0.25 for a sharp
    edge and growing with blur.

    Works on columns for a side closer to horizontal and on rows otherwise, by swapping the
    roles of u and v (a transposed view of the image).
    """
    band = _edge_band(rgb, p, q, face_centre, half_width_px, margin_px)
    if band is None:
        return np.empty((0, 2)), np.empty(0)
    x, line_position = band.x, band.line_position
    # Pixel k of the band covers [k, k + 1] measured outwards from the face's end, so with the
    # face's covered fraction c_k the edge lies at sum(c_k) from that end. The outside colour
    # comes from the first pixel beyond the edge's spread, measured from the current line, and
    # nothing beyond it counts: a part's side seen as a strip of 1 or 2 pixels between the face
    # and the table (they differ a little in chroma) then counts as outside, and a neighbour's
    # face across a gap of a few pixels (2 mm is 4 px) never enters the sum. Pixels as far
    # inside are pure face and count as exactly 1, which keeps their noise out of the edge.
    near_px = INITIAL_OUTSIDE_PX if near_outside_px is None else near_outside_px
    index = np.arange(x.shape[1])
    first_out = np.clip(np.ceil(line_position + near_px - 0.5).astype(int), 1, x.shape[1] - 1)
    first_mixed = np.clip(np.floor(line_position - near_px + 0.5).astype(int), 0, first_out - 1)
    outside = x[np.arange(len(x)), first_out]
    window = (index[None, :] >= first_mixed[:, None]) & (index[None, :] < first_out[:, None])
    # A pixel covers between none and all of itself: an outside read on a mix beyond (a twin's
    # face across a 1 mm gap, anti-aliased) would otherwise give the pixels before it coverages
    # of -1 or less and pull the edge inwards (0.15 mm on the pyramid's green 2 in MuJoCo). Only
    # such gross ones are set to none or all: clipping the camera noise's small excursions too
    # would bias every noisy edge outwards.
    c = _covered(x, face, outside)
    c = np.where(c < -GROSS_COVERAGE, 0.0, np.where(c > 1.0 + GROSS_COVERAGE, 1.0, c))
    covered = np.where(window, c, 0.0)
    edge = first_mixed + covered.sum(axis=1)
    spread = np.where(window, np.clip(np.minimum(covered, 1.0 - covered), 0.0, None), 0.0).sum(axis=1)
    v_edge = band.v_edge(edge)
    contrast = face[None, :] - outside
    contrast_sq = np.einsum("ij,ij->i", contrast, contrast)
    # A column whose neighbour has nearly the face's colour cannot place the edge, and an edge
    # found outside the band's middle means the band missed the transition.
    good = (contrast_sq > 0.09 * float(face @ face)) & (np.abs(v_edge - band.v_line) < half_width_px - 1.0)
    return band.points(v_edge, good), spread[good]


#: A pixel across a painted edge this far (its share of the face-to-outside contrast) off their mix is neither.
MAX_OFF_MIX = 0.25


def _local_side_points(
    rgb: NDArray[np.uint8],
    p: FloatArray,
    q: FloatArray,
    face_centre: FloatArray,
    half_width_px: int,
    margin_px: float,
    near_outside_px: float | None,
) -> tuple[FloatArray, FloatArray]:
    """``_side_edge_points`` with the face's chroma read per column, a pixel inside the mixed pixels."""
    band = _edge_band(rgb, p, q, face_centre, half_width_px, margin_px)
    if band is None:
        return np.empty((0, 2)), np.empty(0)
    x, line_position = band.x, band.line_position
    near_px = 2.0 if near_outside_px is None else near_outside_px
    index = np.arange(x.shape[1])
    columns = np.arange(len(x))
    first_out = np.clip(np.ceil(line_position + near_px - 0.5).astype(int), 2, x.shape[1] - 1)
    first_mixed = np.clip(np.floor(line_position - near_px + 0.5).astype(int), 1, first_out - 1)
    outside = x[columns, first_out]
    face = x[columns, first_mixed - 1]
    contrast = face - outside
    contrast_sq = np.maximum(np.einsum("ij,ij->i", contrast, contrast), 1e-12)
    covered_all = np.einsum("ijk,ik->ij", x - outside[:, None, :], contrast) / contrast_sq[:, None]
    window = (index[None, :] >= first_mixed[:, None]) & (index[None, :] < first_out[:, None])
    covered = np.where(window, covered_all, 0.0)
    edge = first_mixed + covered.sum(axis=1)
    spread = np.where(window, np.clip(np.minimum(covered, 1.0 - covered), 0.0, None), 0.0).sum(axis=1)
    v_edge = band.v_edge(edge)
    strong = contrast_sq > 0.09 * np.maximum(np.einsum("ij,ij->i", face, face), np.einsum("ij,ij->i", outside, outside))
    # A pixel across the edge that is no mix of this face colour and the outside's (the picture
    # changes within a pixel or two of the edge, a stray texel) cannot place it: its column is left out.
    normal = np.column_stack([-contrast[:, 1], contrast[:, 0]])
    off_mix = np.abs(np.einsum("ijk,ik->ij", x - outside[:, None, :], normal)) / contrast_sq[:, None]
    mixed = np.all(~window | ((off_mix <= MAX_OFF_MIX) & (np.abs(covered_all - 0.5) <= 0.5 + MAX_OFF_MIX)), axis=1)
    good = strong & mixed & (contrast_sq > 4.0**2) & (np.abs(v_edge - band.v_line) < half_width_px - 1.0)
    return band.points(v_edge, good), spread[good]


def _fit_side(points: FloatArray, by_columns: bool) -> FloatArray | None:
    """Least-squares line through edge points with error in v (columns) or u (rows), trimmed."""
    if len(points) < 5:
        return None
    x, y = (points[:, 0], points[:, 1]) if by_columns else (points[:, 1], points[:, 0])
    keep = np.ones(len(x), dtype=bool)
    for _ in range(3):
        slope, offset = np.polyfit(x[keep], y[keep], 1)
        residual = np.abs(y - (offset + slope * x))
        # Trim beyond 3.5 robust sigmas (noise, a touching part's edge); never below 0.05 px.
        limit = max(3.5 * 1.4826 * float(_median(residual[keep])), 0.05)
        new_keep = residual <= limit
        if new_keep.sum() < 5 or np.array_equal(new_keep, keep):
            break
        keep = new_keep
    # y = offset + slope * x as a homogeneous line in (u, v).
    return np.array([slope, -1.0, offset]) if by_columns else np.array([-1.0, slope, offset])


def refine_edge_lines(
    rgb: NDArray[np.uint8],
    corners_px: FloatArray,
    undistort: Undistort | None = None,
    passes: tuple[tuple[int, float], ...] = ((5, 10.0), (4, 8.0)),
) -> FloatArray | None:
    """Corners where the four sub-pixel edge lines meet; None when a side has too few points.

    ``corners_px`` (4x2, ordered around the face) need only be within a pixel: each pass
    ``(half_width_px, margin_px)`` re-centres the bands on the previous lines. With ``undistort``
    the last pass's edge points are undistorted before the lines are fitted, so the corners
    come back in undistorted pixel coordinates.
    """
    corners = np.asarray(corners_px, dtype=float).reshape(4, 2)
    face = face_chroma(rgb, corners)
    near_outside_px: float | None = None
    for index, (half_width_px, margin_px) in enumerate(passes):
        centre = corners.mean(axis=0)
        lines, spreads = [], []
        for k in range(4):
            p, q = corners[k], corners[(k + 1) % 4]
            points, spread = _side_edge_points(rgb, p, q, centre, face, half_width_px, margin_px, near_outside_px)
            spreads.append(spread)
            by_columns = abs(q[0] - p[0]) >= abs(q[1] - p[1])
            if undistort is not None and index == len(passes) - 1 and len(points):
                points = undistort(points)
            line = _fit_side(points, by_columns)
            if line is None:
                return None
            lines.append(line)
        corners = _intersect_sides(lines)
        # After the first pass, take each column's outside colour just beyond the edge's
        # spread (1 px for a sharp edge, about 2.8 px for a blur of sigma 0.8 px): near enough
        # to miss what lies beyond a thin neighbour, far enough to be clear of the blur. The
        # spread is a property of the lens, so the face's median serves all four sides.
        excess = max(0.0, float(_median(np.concatenate(spreads))) - SHARP_EDGE_SPREAD)
        near_outside_px = 1.0 + 4.0 * excess
    return corners


def refine_corner_subpix(rgb: NDArray[np.uint8], corners_px: FloatArray, window_px: int = 5) -> FloatArray:
    """``cv2.cornerSubPix`` on the face-coverage image (1 on the face, 0 on grey) of a crop."""
    corners = np.asarray(corners_px, dtype=float).reshape(4, 2)
    face = face_chroma(rgb, corners)
    margin = 2 * window_px + 4
    height, width = rgb.shape[:2]
    x0, y0 = np.maximum(np.floor(corners.min(axis=0)).astype(int) - margin, 0)
    x1, y1 = np.minimum(np.ceil(corners.max(axis=0)).astype(int) + margin + 1, [width, height])
    coverage = (chroma(rgb[y0:y1, x0:x1]) @ face / float(face @ face)).astype(np.float32)
    start = (corners - [x0, y0]).astype(np.float32).reshape(-1, 1, 2)
    criteria = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_COUNT, 50, 1e-4)
    refined = cv2.cornerSubPix(coverage, start, (window_px, window_px), (-1, -1), criteria)
    return refined.reshape(4, 2).astype(float) + [x0, y0]


def refine_contour_lines(contour_px: NDArray[np.integer], corners_px: FloatArray, margin_px: float = 8.0) -> FloatArray:
    """``cv2.fitLine`` through the mask contour's points of each side, intersected.

    The contour runs through the outermost mask pixels, half a pixel inside the edge a 50 %
    threshold would give, so each line is moved out by half a pixel.
    """
    corners = np.asarray(corners_px, dtype=float).reshape(4, 2)
    contour = np.asarray(contour_px, dtype=float).reshape(-1, 2)
    centre = corners.mean(axis=0)
    lines = []
    for k in range(4):
        p, q = corners[k], corners[(k + 1) % 4]
        direction = (q - p) / np.linalg.norm(q - p)
        normal = np.array([-direction[1], direction[0]])
        along = (contour - p) @ direction
        across = (contour - p) @ normal
        side = (along > margin_px) & (along < np.linalg.norm(q - p) - margin_px) & (np.abs(across) < 3.0)
        points = contour[side]
        if len(points) < 2:
            lines.append(_line_through(p, q))
            continue
        vx, vy, x0, y0 = cv2.fitLine(points.astype(np.float32), cv2.DIST_L2, 0, 0.01, 0.01).ravel()
        outward = (
            np.array([vy, -vx]) if np.array([vy, -vx]) @ (np.array([x0, y0]) - centre) > 0 else np.array([-vy, vx])
        )
        start = np.array([x0, y0]) + 0.5 * outward
        lines.append(_line_through(start, start + [vx, vy]))
    return _intersect_sides(lines)
