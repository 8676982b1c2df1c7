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
    for centre_t in sorted((float(t) for t in centres), key=lambda t: (abs(t), t)):
        band = half_pad
        slab = _slab(points, closing, along, centre_t, band)
        if slab is None:
            continue
        top, bottom = float(np.max(slab[:, 0])), float(np.min(slab[:, 0]))
        if top - bottom > max_width_m:
            continue
        wider = _slab(points, closing, along, centre_t, band + 0.003)
        assert wider is not None
        if float(np.max(wider[:, 0])) > top + 2e-4 or float(np.min(wider[:, 0])) < bottom - 2e-4:
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
    points: FloatArray, closing: FloatArray, along: FloatArray, centre_t: float, half_m: float
) -> FloatArray | None:
    """The outline's points (as ``[across, t]``) within ``|t - centre_t| <= half_m``, cut where its edges cross."""
    count = len(points)
    out: list[tuple[float, float]] = []
    for k in range(count):
        a, b = points[k], points[(k + 1) % count]
        ta, tb = float(a @ along), float(b @ along)
        if abs(ta - centre_t) <= half_m:
            out.append((float(a @ closing), ta))
        for t in (centre_t - half_m, centre_t + half_m):
            if (ta - t) * (tb - t) < 0:
                s = (t - ta) / (tb - ta)
                out.append((float((a + s * (b - a)) @ closing), t))
    return np.array(out) if out else None


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
