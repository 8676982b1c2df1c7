"""The antipodal grasp search on a polygon: where two pads can close on a prism's outline (metres, radians).

The closing axes tried are the edges' normals and the bisectors of edges facing each other within
``ANTIPODAL_HALF_ANGLE_RAD``. Along each, the pads (their width across it) stand at the place
nearest the centroid where both meet a local extreme of the outline, their contacts face each
other across the part, and the part is no wider there than the gripper closes across.
"""

from __future__ import annotations

import functools
import math

import numpy as np

from bt_arrange.geometry import FloatArray
from bt_arrange.shapes.base import Grasp
from bt_arrange.shapes.gripper import Gripper

#: The pads hold where edges face each other within this angle of antipodal (a cone of friction 0.3,
#: well inside the pads' measured 1.2 on wood, so a part never slips out turning).
ANTIPODAL_HALF_ANGLE_RAD = math.atan(0.3)
#: A grasp needs the two edges to overlap this much along the pads (a third of a 22 mm pad).
MIN_GRASP_OVERLAP_M = 0.008
#: Beside the pads, this much further along them each way, the outline may rise no more than
#: ``MAX_RISE_M`` above (or below) what the pads hold: else the pads' edges, not their faces, meet it.
BESIDE_PADS_M = 0.003
MAX_RISE_M = 2e-4


@functools.lru_cache(maxsize=1024)
def antipodal_grasps(outline: tuple[tuple[float, float], ...], height_m: float, gripper: Gripper) -> tuple[Grasp, ...]:
    """The grasps on a counter-clockwise outline about its centroid, nearest first; kept per outline and gripper.

    Every step asks, and the search scans the outline.
    """
    return _search(np.array(outline), height_m, gripper)


def _search(points: FloatArray, height: float, gripper: Gripper) -> tuple[Grasp, ...]:
    """Every grasp along the closing axes, nearest the centroid first (``antipodal_grasps``)."""
    found: dict[tuple[float, float], tuple[float, float, Grasp]] = {}
    half_pad = gripper.pad_width_m / 2
    height_m = max(height / 2, gripper.lowest_tcp_m)
    for closing in _closing_axes(points):
        along = np.array([-closing[1], closing[0]])
        grasp = _grasp_along(points, closing, along, half_pad, height_m, gripper.max_grasp_width_m)
        if grasp is None:
            continue
        key = (round(grasp.yaw_offset_rad, 6), round(grasp.centre_m[0], 4))
        distance = float(np.hypot(*grasp.centre_m))
        if key not in found or distance < found[key][0]:
            found[key] = (distance, grasp.width_m, grasp)
    ordered = sorted(found.values(), key=lambda item: (round(item[0], 6), item[1]))
    return tuple(grasp for _, _, grasp in ordered)


def _closing_axes(points: FloatArray) -> list[FloatArray]:
    """Unit closing directions, one per half-turn class: edge normals and antipodal bisectors.

    The candidates are every edge's normal, then the bisector of every pair of edges facing each
    other within ``ANTIPODAL_HALF_ANGLE_RAD`` (in the order of the pairs, ``i < j``); each is kept
    unless it lies within a degree of one kept before it. Every pair is judged at once (numpy, O(n^2)
    in C), and a comparison that comes within ``DECIDED_BY_M`` of its bound is made again one pair
    at a time, so the axes kept, and their figures, are the ones a loop over the pairs keeps.
    """
    directions = np.roll(points, -1, axis=0) - points
    normals = np.column_stack([directions[:, 1], -directions[:, 0]])
    normals /= np.linalg.norm(normals, axis=1)[:, None]
    count = len(normals)
    facing = -math.cos(2 * ANTIPODAL_HALF_ANGLE_RAD)
    first, second = np.triu_indices(count, k=1)  # the pairs i < j in the loop's order
    products = np.einsum("ij,ij->i", normals[first], normals[second])
    chosen = products < facing
    for k in np.flatnonzero(np.abs(products - facing) <= DECIDED_BY_M):
        chosen[k] = float(normals[first[k]] @ normals[second[k]]) < facing
    pairs = np.column_stack([first[chosen], second[chosen]])
    bisectors = normals[pairs[:, 0]] - normals[pairs[:, 1]]
    rough = np.vstack([normals, bisectors / np.linalg.norm(bisectors, axis=1)[:, None]])
    rough[(rough[:, 0] < -1e-12) | ((np.abs(rough[:, 0]) <= 1e-12) & (rough[:, 1] < 0))] *= -1

    def exact(k: int) -> FloatArray:
        """Candidate ``k`` as the loop computes it: a normal, or a pair's bisector normalised on its own."""
        if k < count:
            axis = normals[k]
        else:
            bisector = normals[pairs[k - count, 0]] - normals[pairs[k - count, 1]]
            axis = bisector / np.linalg.norm(bisector)
        if axis[0] < -1e-12 or (abs(axis[0]) <= 1e-12 and axis[1] < 0):
            axis = -axis  # the pads are symmetric under a half turn
        return axis

    # A candidate whose half-turn could go either way by rounding is judged exactly throughout.
    doubtful = np.abs(np.abs(rough[:, 0]) - 1e-12) <= DECIDED_BY_M
    for k in np.flatnonzero(doubtful):
        rough[k] = exact(int(k))
    same = math.cos(math.radians(1.0))
    alive = np.ones(len(rough), dtype=bool)
    unique: list[FloatArray] = []
    start = 0
    while True:
        remaining = np.flatnonzero(alive[start:])
        if not len(remaining):
            return unique
        k = start + int(remaining[0])
        axis = exact(k)
        unique.append(axis)
        later = rough[k + 1 :] @ axis
        dropped = later > same
        for m in np.flatnonzero((np.abs(later - same) <= DECIDED_BY_M) & alive[k + 1 :]):
            dropped[m] = float(exact(k + 1 + int(m)) @ axis) > same
        alive[k + 1 :] &= ~dropped
        start = k + 1


def _grasp_along(
    points: FloatArray, closing: FloatArray, along: FloatArray, half_pad: float, height_m: float, max_width_m: float
) -> Grasp | None:
    """The grasp closing along ``closing`` nearest the centroid, or None."""
    t_values = points @ along
    low, high = float(np.min(t_values)), float(np.max(t_values))
    if high - low < MIN_GRASP_OVERLAP_M:
        return None
    step = 0.0005
    centres = np.arange(low, high + step / 2, step)
    # Every centre judged at once, roughly; only those not clearly refused are judged exactly below.
    undecided = ~_clearly_refused(points, closing, along, centres, half_pad, max_width_m)
    order = np.lexsort((centres, np.abs(centres)))  # nearest the centroid first, the lower of two as near
    left = order[undecided[order]]
    if not len(left):
        return None
    projections = _Projected(points, closing, along, t_values)
    for centre_t in (float(centres[k]) for k in left):
        band = half_pad
        slab = _slab(points, closing, along, centre_t, band, projections)
        if slab is None:
            continue
        top, bottom = float(np.max(slab[:, 0])), float(np.min(slab[:, 0]))
        if top - bottom > max_width_m:
            continue
        wider = _slab(points, closing, along, centre_t, band + BESIDE_PADS_M, projections)
        assert wider is not None
        if float(np.max(wider[:, 0])) > top + MAX_RISE_M or float(np.min(wider[:, 0])) < bottom - MAX_RISE_M:
            continue  # the outline rises beyond the pads: their edges would meet it, not their faces
        upper = slab[slab[:, 0] >= top - 5e-4, 1]
        lower = slab[slab[:, 0] <= bottom + 5e-4, 1]
        if not _facing(float(upper.min()), float(upper.max()), float(lower.min()), float(lower.max())):
            continue
        middle_t = (max(upper.min(), lower.min()) + min(upper.max(), lower.max())) / 2
        centre = closing * (top + bottom) / 2 + along * float(middle_t)
        yaw = math.atan2(float(closing[1]), float(closing[0]))
        axis = "x" if abs(math.sin(yaw)) < 1e-9 else "y" if abs(math.cos(yaw)) < 1e-9 else f"{math.degrees(yaw):.1f}"
        return Grasp(axis, yaw, top - bottom, height_m, (float(centre[0]), float(centre[1])))
    return None


class _Projected:
    """Each point's place along the pads (``t``) and across them as the exact loop has them: a dot each, on demand.

    ``rough``: every point's ``t`` at once (a product of matrices, within a rounding of the exact
    figures), which picks the edges a slab may hold; only those edges' points are projected exactly.
    """

    def __init__(self, points: FloatArray, closing: FloatArray, along: FloatArray, rough: FloatArray) -> None:
        self.points, self.closing, self.along = points, closing, along
        self.rough, self.rough_next = rough, np.roll(rough, -1)
        self.t, self.c = np.full(len(points), np.nan), np.full(len(points), np.nan)

    def exact(self, indices: np.ndarray) -> None:
        """Project the points ``indices`` exactly, those not yet projected."""
        for k in indices[np.isnan(self.t[indices])].tolist():
            point = self.points[k]
            self.t[k], self.c[k] = float(point @ self.along), float(point @ self.closing)


def _slab(
    points: FloatArray,
    closing: FloatArray,
    along: FloatArray,
    centre_t: float,
    half_m: float,
    projections: _Projected | None = None,
) -> FloatArray | None:
    """The outline's points (as ``[across, t]``) within ``|t - centre_t| <= half_m``, cut where its edges cross.

    ``projections``: each point's ``t`` and ``across`` for the closing axis (the same figures as
    here), kept from one slab to the next. The edges are judged together (numpy), on the exact
    figures and in the same arithmetic as one at a time, each crossing's ``across`` a dot of its own.
    """
    count = len(points)
    seen = projections or _Projected(points, closing, along, points @ along)
    # Beyond these by a picometre, a point is outside the slab whatever the rounding of the tests below.
    low_t, high_t = centre_t - half_m - 1e-12, centre_t + half_m + 1e-12
    # The edges that may start within the slab or cross a side, by the rough figures and a margin of
    # ``DECIDED_BY_M``; the exact tests below judge each of them.
    low_rough, high_rough = low_t - DECIDED_BY_M, high_t + DECIDED_BY_M
    starts, ends = seen.rough, seen.rough_next
    edges = np.flatnonzero(
        ~(((starts < low_rough) & (ends < low_rough)) | ((starts > high_rough) & (ends > high_rough)))
    )
    following = (edges + 1) % count
    seen.exact(np.concatenate([edges, following]))
    ta, tb = seen.t[edges], seen.t[following]
    inside = np.abs(ta - centre_t) <= half_m
    values, places = [seen.c[edges][inside]], [ta[inside]]
    for t in (centre_t - half_m, centre_t + half_m):
        crossing = (ta - t) * (tb - t) < 0
        a, b = points[edges[crossing]], points[following[crossing]]
        s = (t - ta[crossing]) / (tb[crossing] - ta[crossing])
        cut = a + s[:, None] * (b - a)
        values.append(np.array([float(point @ closing) for point in cut]))
        places.append(np.full(len(cut), t))
    slab = np.column_stack([np.concatenate(values), np.concatenate(places)])
    return slab if len(slab) else None


#: How far (metres) every rough figure of ``_clearly_refused`` must lie from each bound it is compared
#: with for its verdict to stand: a million times the rounding that tells it from the exact figure.
DECIDED_BY_M = 1e-9


def _clearly_refused(
    points: FloatArray, closing: FloatArray, along: FloatArray, centres: np.ndarray, half_pad: float, max_width_m: float
) -> np.ndarray:
    """For each centre along the pads, True when ``_grasp_along``'s checks refuse it by more than ``DECIDED_BY_M``.

    The same checks on every centre at once, in O((n + centres) log n): the points sorted along the
    pads, the highest and lowest of those within a slab read from sparse tables, the edges' crossings
    of the slabs' sides counted out edge by edge, and the pads' contacts found by binary lifting. Its
    figures are rounded differently from the exact loop's (a product of matrices, not a dot per
    point): a centre any of whose comparisons comes within ``DECIDED_BY_M`` of its bound is left to
    the exact loop, so the grasp found is the one the loop alone finds.
    """
    t, c = points @ along, points @ closing
    count, near = len(t), DECIDED_BY_M
    order = np.argsort(t, kind="stable")
    ts = t[order]
    # Sparse tables of the points in order along the pads: level k, place i holds the highest across of
    # [i, i + 2^k); the second half the highest of the negated, so that the lowest is read the same way.
    levels = max(1, int(count).bit_length())
    table = np.full((levels, 2 * count + 1), -np.inf)
    table[0, : 2 * count] = np.concatenate([c[order], -c[order]])
    for k in range(1, levels):
        size = 1 << (k - 1)
        table[k, : 2 * count - size] = np.maximum(table[k - 1, : 2 * count - size], table[k - 1, size : 2 * count])
    t_next, c_next = np.roll(t, -1), np.roll(c, -1)
    edge_low, edge_high = np.minimum(t, t_next), np.maximum(t, t_next)
    unclear = np.zeros(len(centres), dtype=bool)

    def highest(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
        """The highest table value in each [lo, hi) (-inf where empty)."""
        length = np.maximum(hi - lo, 1)
        k = np.frexp(length.astype(float))[1] - 1
        found = np.maximum(table[k, lo], table[k, hi - (1 << k)])
        return np.where(hi > lo, found, -np.inf)

    def crossings(bounds: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The highest and lowest across where edges cross each bound (strictly); -inf and inf where none do."""
        first = np.searchsorted(bounds, edge_low, side="right")
        counts = np.maximum(np.searchsorted(bounds, edge_high, side="left") - first, 0)
        top, bottom = np.full(len(bounds), -np.inf), np.full(len(bounds), np.inf)
        total = int(counts.sum())
        if total:
            edges = np.repeat(np.arange(count), counts)
            at = np.arange(total) - np.repeat(np.cumsum(counts) - counts - first, counts)
            share = (bounds[at] - t[edges]) / (t_next[edges] - t[edges])
            values = c[edges] + share * (c_next[edges] - c[edges])
            np.maximum.at(top, at, values)
            np.minimum.at(bottom, at, values)
        return top, bottom

    def slab(half_m: float) -> tuple[np.ndarray, ...]:
        """Each centre's slab: its points' range in order, highest and lowest, and the crossings on either side."""
        nonlocal unclear
        low_side, high_side = centres - half_m, centres + half_m
        for side in (low_side, high_side):  # a point on a side is inside to one rounding and outside to another
            unclear |= np.searchsorted(ts, side - near, side="left") != np.searchsorted(ts, side + near, side="right")
        lo = np.searchsorted(ts, low_side, side="left")
        hi = np.searchsorted(ts, high_side, side="right")
        (low_top, low_bottom), (high_top, high_bottom) = crossings(low_side), crossings(high_side)
        top = np.maximum(np.maximum(highest(lo, hi), low_top), high_top)
        bottom = np.minimum(np.minimum(-highest(lo + count, hi + count), low_bottom), high_bottom)
        return lo, hi, top, bottom, low_top, -low_bottom, high_top, -high_bottom

    def lifted(lo: np.ndarray, hi: np.ndarray, floor: np.ndarray, backwards: bool) -> np.ndarray:
        """The first (or, ``backwards``, one past the last) place in [lo, hi) whose value reaches ``floor``."""
        place = hi.copy() if backwards else lo.copy()
        for k in range(levels - 1, -1, -1):
            size = 1 << k
            start = place - size if backwards else place  # from -count to 2 count: always a place of the table
            fits = start >= lo if backwards else start + size <= hi
            place = np.where(fits & (table[k, start] < floor), place - size if backwards else place + size, place)
        return place

    with np.errstate(invalid="ignore"):
        lo, hi, top, bottom, *sides = slab(half_pad)
        empty = ~np.isfinite(top)
        top, bottom = np.where(empty, 0.0, top), np.where(empty, 0.0, bottom)
        width = top - bottom
        unclear |= np.abs(width - max_width_m) <= near
        _, _, wider_top, wider_bottom, *_ = slab(half_pad + BESIDE_PADS_M)
        high, low = top + MAX_RISE_M, bottom - MAX_RISE_M
        unclear |= (np.abs(wider_top - high) <= near) | (np.abs(wider_bottom - low) <= near)
        rises = (wider_top > high) | (wider_bottom < low)
        # The pads' contacts: the slab's members within 0.5 mm of its top (and of its bottom, negated),
        # found twice, their bound moved ``near`` either way: where the two differ, the call is close.
        low_top, low_neg, high_top, high_neg = sides
        # Four searches a centre, stacked: the upper and the lower contacts, each with its bound moved both ways.
        offset = np.repeat([0, count, 0, count], len(centres))
        floor = np.concatenate([top - 5e-4 - near, -(bottom + 5e-4) - near, top - 5e-4 + near, -(bottom + 5e-4) + near])
        at_low, at_high = (
            np.tile(np.concatenate([low_top, low_neg]), 2),
            np.tile(np.concatenate([high_top, high_neg]), 2),
        )
        starts, ends = np.tile(lo, 4) + offset, np.tile(hi, 4) + offset
        first = lifted(starts, ends, floor, backwards=False)
        after = lifted(starts, ends, floor, backwards=True)
        low_side, high_side = np.tile(centres - half_pad, 4), np.tile(centres + half_pad, 4)
        start = np.where(first < ends, ts[(first - offset) % count], high_side)
        end = np.where(after > starts, ts[(after - 1 - offset) % count], low_side)
        span_low = np.where(at_low >= floor, low_side, start).reshape(4, -1)
        span_high = np.where(at_high >= floor, high_side, end).reshape(4, -1)
        unclear |= np.any(span_low[:2] != span_low[2:], axis=0) | np.any(span_high[:2] != span_high[2:], axis=0)
        upper_low, lower_low, upper_high, lower_high = span_low[0], span_low[1], span_high[0], span_high[1]
    facing, facing_unclear = _facing_all(upper_low, upper_high, lower_low, lower_high, near)
    unclear |= facing_unclear
    refused = empty | (width > max_width_m) | rises | ~facing
    return refused & ~unclear


def _facing_all(
    upper_low: np.ndarray, upper_high: np.ndarray, lower_low: np.ndarray, lower_high: np.ndarray, near: float
) -> tuple[np.ndarray, np.ndarray]:
    """``_facing`` of every centre at once, and where one of its comparisons comes within ``near`` of its bound."""
    corner_m, margin_m = 5e-4, 0.002
    upper_span, lower_span = upper_high - upper_low, lower_high - lower_low
    upper_corner, lower_corner = upper_span < corner_m, lower_span < corner_m
    unclear = (np.abs(upper_span - corner_m) <= near) | (np.abs(lower_span - corner_m) <= near)
    point = np.where(upper_corner, upper_low, lower_low)
    low = np.where(upper_corner, lower_low, upper_low) + margin_m
    high = np.where(upper_corner, lower_high, upper_high) - margin_m
    one_corner = (low <= point) & (point <= high)
    unclear |= (upper_corner ^ lower_corner) & ((np.abs(point - low) <= near) | (np.abs(point - high) <= near))
    overlap = np.minimum(upper_high, lower_high) - np.maximum(upper_low, lower_low)
    edges = overlap >= MIN_GRASP_OVERLAP_M
    unclear |= ~upper_corner & ~lower_corner & (np.abs(overlap - MIN_GRASP_OVERLAP_M) <= near)
    facing = np.where(upper_corner & lower_corner, False, np.where(upper_corner | lower_corner, one_corner, edges))
    return facing, unclear


def _facing(upper_low: float, upper_high: float, lower_low: float, lower_high: float) -> bool:
    """True when the two pads' contacts face each other across the part: their spans along the pads overlap.

    Two edges must overlap ``MIN_GRASP_OVERLAP_M``; a corner (a span of no length) must lie 2 mm
    or more inside the other side's span.
    """
    corner_m, margin_m = 5e-4, 0.002
    if upper_high - upper_low < corner_m or lower_high - lower_low < corner_m:
        if upper_high - upper_low < corner_m and lower_high - lower_low < corner_m:
            return False  # two corners: the part would turn between the pads
        point = upper_low if upper_high - upper_low < corner_m else lower_low
        span = (lower_low, lower_high) if upper_high - upper_low < corner_m else (upper_low, upper_high)
        return span[0] + margin_m <= point <= span[1] - margin_m
    return min(upper_high, lower_high) - max(upper_low, lower_low) >= MIN_GRASP_OVERLAP_M
