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
    """Unit closing directions, one per half-turn class: edge normals and antipodal bisectors."""
    directions = np.roll(points, -1, axis=0) - points
    normals = np.column_stack([directions[:, 1], -directions[:, 0]])
    normals /= np.linalg.norm(normals, axis=1)[:, None]
    axes = list(normals)
    count = len(normals)
    for i in range(count):
        for j in range(i + 1, count):
            if float(normals[i] @ normals[j]) < -math.cos(2 * ANTIPODAL_HALF_ANGLE_RAD):
                bisector = normals[i] - normals[j]
                axes.append(bisector / np.linalg.norm(bisector))
    unique: list[FloatArray] = []
    for axis in axes:
        if axis[0] < -1e-12 or (abs(axis[0]) <= 1e-12 and axis[1] < 0):
            axis = -axis  # the pads are symmetric under a half turn
        if not any(float(axis @ other) > math.cos(math.radians(1.0)) for other in unique):
            unique.append(axis)
    return unique


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
    order = sorted(range(len(centres)), key=lambda k: (abs(float(centres[k])), float(centres[k])))
    # Each point's place along the pads and across them, as the exact loop computes them (a dot each).
    projections = ([float(p @ along) for p in points], [float(p @ closing) for p in points])
    for centre_t in (float(centres[k]) for k in order if undecided[k]):
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


def _slab(
    points: FloatArray,
    closing: FloatArray,
    along: FloatArray,
    centre_t: float,
    half_m: float,
    projections: tuple[list[float], list[float]] | None = None,
) -> FloatArray | None:
    """The outline's points (as ``[across, t]``) within ``|t - centre_t| <= half_m``, cut where its edges cross.

    ``projections``: each point's ``t`` and ``across``, computed once for the closing axis (the same
    figures as here); an edge wholly beyond the slab adds nothing and is passed over.
    """
    count = len(points)
    t_of, c_of = projections or ([float(p @ along) for p in points], [float(p @ closing) for p in points])
    # Beyond these by a picometre, a point is outside the slab whatever the rounding of the tests below.
    low_t, high_t = centre_t - half_m - 1e-12, centre_t + half_m + 1e-12
    out: list[tuple[float, float]] = []
    for k in range(count):
        ta, tb = t_of[k], t_of[(k + 1) % count]
        if (ta < low_t and tb < low_t) or (ta > high_t and tb > high_t):
            continue  # neither its start within the slab nor a crossing of either side
        a, b = points[k], points[(k + 1) % count]
        if abs(ta - centre_t) <= half_m:
            out.append((c_of[k], ta))
        for t in (centre_t - half_m, centre_t + half_m):
            if (ta - t) * (tb - t) < 0:
                s = (t - ta) / (tb - ta)
                out.append((float((a + s * (b - a)) @ closing), t))
    return np.array(out) if out else None


#: How far (metres) every rough figure of ``_clearly_refused`` must lie from each bound it is compared
#: with for its verdict to stand: a million times the rounding that tells it from the exact figure.
DECIDED_BY_M = 1e-9


def _clearly_refused(
    points: FloatArray, closing: FloatArray, along: FloatArray, centres: np.ndarray, half_pad: float, max_width_m: float
) -> np.ndarray:
    """For each centre along the pads, True when ``_grasp_along``'s checks refuse it by more than ``DECIDED_BY_M``.

    The same checks on every centre at once (numpy, in O(centres x points)), on figures rounded
    differently from the exact loop's (a product of matrices, not a dot per point): a centre any of
    whose comparisons comes within ``DECIDED_BY_M`` of its bound is left to the exact loop, so the
    grasp found is the one the loop alone finds, only without judging the centres refused plainly.
    """
    t = points @ along
    c = points @ closing
    t_next, c_next = np.roll(t, -1), np.roll(c, -1)
    near = DECIDED_BY_M
    mid = centres[:, None]
    unclear = np.zeros(len(centres), dtype=bool)

    def slab(half_m: float) -> tuple[np.ndarray, np.ndarray]:
        """Each centre's slab: its points' ``c`` (NaN where none) and ``t``, vertices then crossings."""
        nonlocal unclear
        inside = np.abs(t - mid) <= half_m
        unclear |= np.any(np.abs(np.abs(t - mid) - half_m) <= near, axis=1)
        values, places = [np.where(inside, c, np.nan)], [np.broadcast_to(t, inside.shape)]
        for bound in (mid - half_m, mid + half_m):
            crosses = (t - bound) * (t_next - bound) < 0
            unclear |= np.any((np.abs(t - bound) <= near) | (np.abs(t_next - bound) <= near), axis=1)
            with np.errstate(divide="ignore", invalid="ignore"):
                share = (bound - t) / (t_next - t)
            values.append(np.where(crosses, c + share * (c_next - c), np.nan))
            places.append(np.broadcast_to(bound, inside.shape))
        return np.concatenate(values, axis=1), np.concatenate(places, axis=1)

    with np.errstate(invalid="ignore"):
        values, places = slab(half_pad)
        empty = np.all(np.isnan(values), axis=1)
        top, bottom = (
            np.nanmax(np.where(empty[:, None], 0.0, values), axis=1),
            np.nanmin(np.where(empty[:, None], 0.0, values), axis=1),
        )
        width = top - bottom
        unclear |= np.abs(width - max_width_m) <= near
        wider, _ = slab(half_pad + BESIDE_PADS_M)
        wider_top = np.nanmax(np.where(np.isnan(wider), -np.inf, wider), axis=1)
        wider_bottom = np.nanmin(np.where(np.isnan(wider), np.inf, wider), axis=1)
        high, low = top + MAX_RISE_M, bottom - MAX_RISE_M
        unclear |= (np.abs(wider_top - high) <= near) | (np.abs(wider_bottom - low) <= near)
        rises = (wider_top > high) | (wider_bottom < low)
        upper = values >= (top - 5e-4)[:, None]
        lower = values <= (bottom + 5e-4)[:, None]
        unclear |= np.any(np.abs(values - (top - 5e-4)[:, None]) <= near, axis=1)
        unclear |= np.any(np.abs(values - (bottom + 5e-4)[:, None]) <= near, axis=1)

        def span(members: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
            return np.where(members, places, np.inf).min(axis=1), np.where(members, places, -np.inf).max(axis=1)

        (upper_low, upper_high), (lower_low, lower_high) = span(upper), span(lower)
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
