"""The sides of an unknown outline measured below a pixel: lines, side samplers, colours along the edges.

The image side of ``bt_arrange.perception.outline_unknown``: a side's sub-pixel edge points against
one face colour (``corners._side_edge_points``, the box's measure) or against the face's colour read
per column just inside the edge (a painted face, ``corners._local_side_points``), total least squares lines
through points on the table plane, and the face's colour sampled along each edge.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from bt_arrange.geometry import FloatArray
from bt_arrange.perception.colours import Mask
from bt_arrange.perception.corners import _local_side_points, _median, _side_edge_points
from bt_arrange.perception.outline_face import _outside_is_clear
from bt_arrange.perception.values import PreparedView

#: A line: a point on it and its unit direction.
Line = tuple[FloatArray, FloatArray]
#: Fewer sub-pixel points than this on a side: the side cannot be measured.
MIN_SIDE_POINTS = 6
#: The inside colour samples: this far inside the edge (px), this far apart along it, not this near a corner.
COLOUR_DEPTH_PX = 1.5
COLOUR_STEP_PX = 1.0
COLOUR_END_PX = 3.0


def line_of_points(points: FloatArray) -> Line:
    """Total least squares: a point on the line and its unit direction."""
    centre = points.mean(axis=0)
    _, _, vt = np.linalg.svd(points - centre, full_matrices=False)
    return centre, vt[0]


def intersect(a: Line, b: Line) -> FloatArray | None:
    """Where two lines (point, direction) meet; None when they are nearly parallel."""
    (pa, da), (pb, db) = a, b
    det = da[0] * (-db[1]) - da[1] * (-db[0])
    if abs(det) < math.sin(math.radians(2.0)):
        return None
    rhs = pb - pa
    t = (rhs[0] * (-db[1]) - rhs[1] * (-db[0])) / det
    return np.asarray(pa + t * da, dtype=float)


#: Edge points of one side (image px, Nx2) and their spreads: the sampler of a side.
SideSampler = Callable[[FloatArray, FloatArray, FloatArray, int, float, float | None], tuple[FloatArray, FloatArray]]


def fit_line(points: FloatArray, floor_m: float) -> tuple[Line, FloatArray]:
    """Total least squares through points on the plane, trimmed beyond 3.5 robust sigmas; the kept residuals."""
    keep = np.ones(len(points), dtype=bool)
    line = line_of_points(points)
    residual = np.zeros(len(points))
    for _ in range(4):
        point, direction = line
        normal = np.array([-direction[1], direction[0]])
        residual = (points - point) @ normal
        limit = max(3.5 * 1.4826 * float(_median(np.abs(residual[keep]))), floor_m)
        new_keep = np.abs(residual) <= limit
        if new_keep.sum() < MIN_SIDE_POINTS or np.array_equal(new_keep, keep):
            break
        keep = new_keep
        line = line_of_points(points[keep])
    point, direction = line
    normal = np.array([-direction[1], direction[0]])
    return line, ((points - point) @ normal)[keep]


def clear_along_bands(points: FloatArray, corners: FloatArray, side: int, reach_px: float) -> NDArray[np.bool_]:
    """Which edge points of side ``side`` read no other side: none crosses their band within ``reach_px``.

    A point's edge is read along its band, the pixel column across the side (a row for a steep
    side), from ``reach_px`` inside the edge to ``reach_px`` beyond it. Another side's edge in that
    stretch would mix into its sum; beside the band, however near, it does not. Near an obtuse
    corner a side's own columns run clear of its neighbour while their distance to it is small.
    """
    count = len(corners)
    p, q = corners[side], corners[(side + 1) % count]
    axis = 0 if abs(q[0] - p[0]) >= abs(q[1] - p[1]) else 1  # the coordinate along the side
    along, across = points[:, axis], points[:, 1 - axis]
    clear = np.ones(len(points), dtype=bool)
    for other in range(count):
        if other == side:
            continue
        a, b = corners[other], corners[(other + 1) % count]
        low, high = sorted((a[axis], b[axis]))
        # The other side's stretch over each band, widened by half a pixel either way (the band's width).
        t_low = np.clip((along - 0.5 - a[axis]) / (b[axis] - a[axis] or 1e-9), 0.0, 1.0)
        t_high = np.clip((along + 0.5 - a[axis]) / (b[axis] - a[axis] or 1e-9), 0.0, 1.0)
        first = a[1 - axis] + t_low * (b[1 - axis] - a[1 - axis])
        last = a[1 - axis] + t_high * (b[1 - axis] - a[1 - axis])
        over = (along + 0.5 >= low) & (along - 0.5 <= high)
        near = np.minimum(first, last) - reach_px <= across
        near &= across <= np.maximum(first, last) + reach_px
        clear &= ~(over & near)
    return clear


def colour_sampler(view: PreparedView, face_chroma: FloatArray) -> SideSampler:
    """The box's edge measure against one face chroma, keeping points whose band ends clear of the colour."""

    def sample(
        p: FloatArray, q: FloatArray, centre: FloatArray, half_width_px: int, margin_px: float, near: float | None
    ) -> tuple[FloatArray, FloatArray]:
        points, spread = _side_edge_points(view.rgb, p, q, centre, face_chroma, half_width_px, margin_px, near)
        if len(points) == 0:
            return points, spread
        free = _outside_is_clear(view.rgb, points, p, q, centre, face_chroma, half_width_px + 1.0)
        return points[free], spread[free]

    return sample


def local_sampler(view: PreparedView, foreground: Mask) -> SideSampler:
    """The edge measure against the face's colour read per column just inside the edge (a painted face).

    The covered fractions across the edge are unmixed between that colour and the outside's, both in
    the chroma plane; a point whose band ends on the foreground (a neighbour) is left out.
    """
    rgb = view.rgb

    def sample(
        p: FloatArray, q: FloatArray, centre: FloatArray, half_width_px: int, margin_px: float, near: float | None
    ) -> tuple[FloatArray, FloatArray]:
        points, spread = _local_side_points(rgb, p, q, centre, half_width_px, margin_px, near)
        if len(points) == 0:
            return points, spread
        along = (q - p) / max(float(np.hypot(*(q - p))), 1e-9)
        normal = np.array([along[1], -along[0]])
        if float(normal @ (centre - (p + q) / 2)) > 0:
            normal = -normal
        probes = np.round(points + (half_width_px + 1.0) * normal).astype(int)
        height, width = foreground.shape[:2]
        u, v = np.clip(probes[:, 0], 0, width - 1), np.clip(probes[:, 1], 0, height - 1)
        free = foreground[v, u] == 0
        return points[free], spread[free]

    return sample


def edge_colours(view: PreparedView, vertices_px: FloatArray) -> tuple[FloatArray, ...]:
    """Per edge, RGB (0..1) sampled bilinearly ``COLOUR_DEPTH_PX`` inside it, a pixel apart, in order."""
    count = len(vertices_px)
    centre = vertices_px.mean(axis=0)
    rgb = view.rgb
    colours = []
    for k in range(count):
        p, q = vertices_px[k], vertices_px[(k + 1) % count]
        length = float(np.hypot(*(q - p)))
        direction = (q - p) / max(length, 1e-9)
        inward = np.array([-direction[1], direction[0]])
        if inward @ (centre - p) < 0:
            inward = -inward
        steps = np.arange(COLOUR_END_PX, length - COLOUR_END_PX + 1e-9, COLOUR_STEP_PX)
        points = p + steps[:, None] * direction + COLOUR_DEPTH_PX * inward
        colours.append(_bilinear(rgb, points))
    return tuple(colours)


def _bilinear(rgb: NDArray[np.uint8], points: FloatArray) -> FloatArray:
    """RGB (0..1) at sub-pixel points (Nx2, pixel centres at integers), bilinear, clamped to the image."""
    height, width = rgb.shape[:2]
    if len(points) == 0:
        return np.empty((0, 3))
    u = np.clip(points[:, 0], 0.0, width - 1.0)
    v = np.clip(points[:, 1], 0.0, height - 1.0)
    u0 = np.minimum(np.floor(u).astype(int), width - 2)
    v0 = np.minimum(np.floor(v).astype(int), height - 2)
    a, b = (u - u0)[:, None], (v - v0)[:, None]
    top = (1 - a) * rgb[v0, u0] + a * rgb[v0, u0 + 1]
    bottom = (1 - a) * rgb[v0 + 1, u0] + a * rgb[v0 + 1, u0 + 1]
    return np.asarray(((1 - b) * top + b * bottom) / 255.0, dtype=float)


#: Edge points this near a pixel boundary (px) are quantised: the image samples pixel centres.
QUANTISED_PX = 0.02
#: The share of a side's points that must be quantised for it to be read as an aliased staircase.
QUANTISED_SHARE = 0.9
#: Slopes tried across the staircase's allowed range (8 px over its length).
SLOPE_GRID = 801


def aliased_line(points: FloatArray, p: FloatArray, q: FloatArray) -> FloatArray:
    """An aliased side's points replaced by points on the centre of the lines its staircase allows.

    Sampled at pixel centres (pybullet's TinyRenderer), each column's edge lies on a pixel boundary
    ``b``, the true line within half a pixel of it, ``b - 0.5 < v(u) <= b + 0.5``: a staircase whose
    runs say little and whose steps say much (where it steps, the line crosses a row of pixel centres
    between two columns). The lines ``v = a + c u`` that keep to every column's half pixel form a convex
    region in ``(a, c)``: for each slope ``c`` on a fine grid, ``a`` lies between the columns' highest
    floor and lowest ceiling. Its centroid is the line returned (the mean of the lines the image
    allows). A least-squares fit would weigh the runs' quantisation instead, and tilt a side that steps
    once or twice (within a few degrees of a row or column) by the runs at its ends. Points that are
    not quantised (an anti-aliased, blurred or noisy image) are kept as they are.
    """
    direction = q - p
    by_columns = abs(direction[0]) >= abs(direction[1])
    along, across = (points[:, 0], points[:, 1]) if by_columns else (points[:, 1], points[:, 0])
    if len(points) < 6:
        return points
    quantised = np.abs((across - 0.5) - np.round(across - 0.5)) < QUANTISED_PX
    if float(np.mean(quantised)) < QUANTISED_SHARE:
        return points
    order = np.argsort(along[quantised])
    u, b = along[quantised][order], np.round(across[quantised][order] - 0.5) + 0.5
    centre = float(u.mean())
    x = u - centre
    # Within a run of one boundary the line is linear: its two ends bind, the columns between do not.
    change = np.r_[True, b[1:] != b[:-1]] | np.r_[b[:-1] != b[1:], True]
    x, b = x[change], b[change]
    span = max(float(x.max() - x.min()), 1.0)
    slope = float(np.polyfit(x, b, 1)[0]) if len(x) >= 2 else 0.0
    low, high = slope - 4.0 / span, slope + 4.0 / span
    for _ in range(2):  # the allowed range, then the grid again across it alone
        slopes = np.linspace(low, high, SLOPE_GRID)
        floor = np.max((b - 0.5)[None, :] - slopes[:, None] * x[None, :], axis=1)
        ceiling = np.min((b + 0.5)[None, :] - slopes[:, None] * x[None, :], axis=1)
        width = np.maximum(ceiling - floor, 0.0)
        total = float(width.sum())
        if total <= 0.0:
            return points  # no line keeps to every column: not a clean staircase
        allowed = np.nonzero(width > 0)[0]
        step = slopes[1] - slopes[0]
        low, high = slopes[allowed[0]] - step, slopes[allowed[-1]] + step
    c = float((slopes * width).sum()) / total
    a = float(((floor + ceiling) / 2 * width).sum()) / total
    span_u = np.linspace(along.min(), along.max(), 12)
    line = a + c * (span_u - centre)
    return np.column_stack([span_u, line]) if by_columns else np.column_stack([line, span_u])
