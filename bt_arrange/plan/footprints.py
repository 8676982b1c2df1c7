"""Footprints on the table and their geometry: a cuboid's rectangle, an irregular part's outline.

Planar, in metres: :class:`Rect` (an oriented rectangle) and :class:`Outline` (the convex pieces
of a prism's top face at a pose) share the frame operations the layout needs (``axes``,
``local``, ``moved``); ``overlap`` and ``gap_m`` test any two by separating axes (the cuboids'
rectangles exactly as before, outlines piece by piece). ``bt_arrange.plan.layout`` places pads and
parts with them. No pybullet, no shapely.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from dataclasses import dataclass


@dataclass(frozen=True)
class Rect:
    """An oriented rectangle on the table: centre ``(x_m, y_m)``, ``yaw_rad``, half sizes along its own x and y."""

    x_m: float
    y_m: float
    yaw_rad: float
    half_x_m: float
    half_y_m: float

    def axes(self) -> tuple[tuple[float, float], tuple[float, float]]:
        """Its own x and y axes as world unit vectors."""
        c, s = math.cos(self.yaw_rad), math.sin(self.yaw_rad)
        return (c, s), (-s, c)

    def corners(self) -> list[tuple[float, float]]:
        """The four corners, counter-clockwise."""
        (ax, ay), (bx, by) = self.axes()
        return [
            (
                self.x_m + i * self.half_x_m * ax + j * self.half_y_m * bx,
                self.y_m + i * self.half_x_m * ay + j * self.half_y_m * by,
            )
            for i, j in ((1, 1), (-1, 1), (-1, -1), (1, -1))
        ]

    def local(self, dx_m: float, dy_m: float, half_x_m: float, half_y_m: float) -> Rect:
        """A rectangle of the same yaw, centred ``(dx, dy)`` from this one's centre in its frame."""
        (ax, ay), (bx, by) = self.axes()
        return Rect(
            self.x_m + dx_m * ax + dy_m * bx, self.y_m + dx_m * ay + dy_m * by, self.yaw_rad, half_x_m, half_y_m
        )

    def moved(self, dx_m: float, dy_m: float) -> Rect:
        """The same rectangle moved by ``(dx, dy)`` in its own frame."""
        return self.local(dx_m, dy_m, self.half_x_m, self.half_y_m)


@dataclass(frozen=True)
class Outline:
    """An irregular part's footprint: its top face's convex ``pieces`` (own frame) at ``(x_m, y_m, yaw_rad)``.

    The same frame operations as a :class:`Rect` (``axes``, ``local``, ``moved``), so the pads'
    rectangles stand beside it as beside a cuboid's; overlaps are tested piece by piece.
    """

    x_m: float
    y_m: float
    yaw_rad: float
    pieces: tuple[tuple[tuple[float, float], ...], ...]

    def axes(self) -> tuple[tuple[float, float], tuple[float, float]]:
        """Its own x and y axes as world unit vectors."""
        c, s = math.cos(self.yaw_rad), math.sin(self.yaw_rad)
        return (c, s), (-s, c)

    def world_pieces(self) -> list[list[tuple[float, float]]]:
        """Each convex piece's corners on the table, counter-clockwise."""
        (ax, ay), (bx, by) = self.axes()
        return [
            [(self.x_m + px * ax + py * bx, self.y_m + px * ay + py * by) for px, py in piece] for piece in self.pieces
        ]

    def local(self, dx_m: float, dy_m: float, half_x_m: float, half_y_m: float) -> Rect:
        """A rectangle of the same yaw, centred ``(dx, dy)`` from this one's origin in its frame."""
        return Rect(self.x_m, self.y_m, self.yaw_rad, 0.0, 0.0).local(dx_m, dy_m, half_x_m, half_y_m)

    def moved(self, dx_m: float, dy_m: float) -> Outline:
        """The same footprint moved by ``(dx, dy)`` in its own frame."""
        (ax, ay), (bx, by) = self.axes()
        return Outline(self.x_m + dx_m * ax + dy_m * bx, self.y_m + dx_m * ay + dy_m * by, self.yaw_rad, self.pieces)


#: A footprint on the table: a cuboid's rectangle or an irregular part's outline.
Footprint = Rect | Outline


def _polygons(shape: Footprint) -> list[list[tuple[float, float]]]:
    return [shape.corners()] if isinstance(shape, Rect) else shape.world_pieces()


def _normals(polygon: Sequence[tuple[float, float]]) -> list[tuple[float, float]]:
    out = []
    for k in range(len(polygon)):
        (x0, y0), (x1, y1) = polygon[k], polygon[(k + 1) % len(polygon)]
        length = math.hypot(x1 - x0, y1 - y0)
        if length > 1e-12:
            out.append(((y1 - y0) / length, (x0 - x1) / length))
    return out


def _convex_overlap(a: Sequence[tuple[float, float]], b: Sequence[tuple[float, float]], clearance_m: float) -> bool:
    """Separating axes on two convex polygons' edge normals, ``a`` grown by ``clearance_m``."""
    for axis in (*_normals(a), *_normals(b)):
        values_a = [x * axis[0] + y * axis[1] for x, y in a]
        values_b = [x * axis[0] + y * axis[1] for x, y in b]
        if max(values_a) + clearance_m <= min(values_b) or max(values_b) + clearance_m <= min(values_a):
            return False
    return True


def _radius(polygon: Sequence[tuple[float, float]]) -> tuple[float, float, float]:
    cx = sum(x for x, _ in polygon) / len(polygon)
    cy = sum(y for _, y in polygon) / len(polygon)
    return cx, cy, max(math.hypot(x - cx, y - cy) for x, y in polygon)


#: What ``overlap``'s test of two whole footprints keeps beyond the pieces' own tests (metres): far
#: above the rounding between a piece's circle worked on the table and in the part's frame.
REACH_SLACK_M = 1e-9


def _reach(shape: Footprint) -> tuple[float, float, float]:
    """A circle on the table holding every circle ``overlap`` draws around one of the footprint's pieces."""
    if isinstance(shape, Rect):
        return shape.x_m, shape.y_m, math.hypot(shape.half_x_m, shape.half_y_m)
    return shape.x_m, shape.y_m, _pieces_reach(shape.pieces)


@functools.lru_cache(maxsize=4096)
def _pieces_reach(pieces: tuple[tuple[tuple[float, float], ...], ...]) -> float:
    """How far from the frame's origin the farthest piece's circle (its corners' mean, to its farthest corner) reaches.

    The same in every pose (a turn and a shift keep distances), so kept per outline: the layout's
    search asks it of the same pieces at thousands of poses.
    """
    reach = 0.0
    for piece in pieces:
        cx, cy, radius = _radius(piece)
        reach = max(reach, math.hypot(cx, cy) + radius)
    return reach


def _project(rect: Rect, axis: tuple[float, float]) -> tuple[float, float]:
    values = [x * axis[0] + y * axis[1] for x, y in rect.corners()]
    return min(values), max(values)


def overlap(a: Footprint, b: Footprint, clearance_m: float = 0.0) -> bool:
    """True when ``a`` and ``b`` come closer than ``clearance_m`` along some separating axis.

    Separating axes on the four edge normals; with a clearance this is ``a`` grown by it on every
    side (square corners: slightly conservative at the corners). An :class:`Outline` is tested
    piece by piece, each convex piece on its own edge normals.
    """
    if not (isinstance(a, Rect) and isinstance(b, Rect)):
        (ax0, ay0, a_reach), (bx0, by0, b_reach) = _reach(a), _reach(b)
        if math.hypot(ax0 - bx0, ay0 - by0) > a_reach + b_reach + clearance_m + REACH_SLACK_M:
            return False  # every pair of pieces' circles below lies apart too: the loop would say so
        for first in _polygons(a):
            ax, ay, ar = _radius(first)
            for second in _polygons(b):
                bx, by, br = _radius(second)
                if math.hypot(ax - bx, ay - by) > ar + br + clearance_m:
                    continue
                if _convex_overlap(first, second, clearance_m):
                    return True
        return False
    if (
        math.hypot(a.x_m - b.x_m, a.y_m - b.y_m)
        > math.hypot(a.half_x_m, a.half_y_m) + math.hypot(b.half_x_m, b.half_y_m) + clearance_m
    ):
        return False
    for axis in (*a.axes(), *b.axes()):
        low_a, high_a = _project(a, axis)
        low_b, high_b = _project(b, axis)
        if high_a + clearance_m <= low_b or high_b + clearance_m <= low_a:
            return False
    return True


def gap_m(a: Footprint, b: Footprint) -> float:
    """The distance between two footprints (0 when they overlap)."""
    if overlap(a, b):
        return 0.0
    if not (isinstance(a, Rect) and isinstance(b, Rect)):
        return _polygon_gap_m(_polygons(a), _polygons(b))

    def point_segment(p: tuple[float, float], q: tuple[float, float], r: tuple[float, float]) -> float:
        dx, dy = r[0] - q[0], r[1] - q[1]
        if dx == 0.0 and dy == 0.0:
            return math.hypot(p[0] - q[0], p[1] - q[1])
        t = max(0.0, min(1.0, ((p[0] - q[0]) * dx + (p[1] - q[1]) * dy) / (dx * dx + dy * dy)))
        return math.hypot(p[0] - q[0] - t * dx, p[1] - q[1] - t * dy)

    best = math.inf
    for first, second in ((a, b), (b, a)):
        corners = second.corners()
        for p in first.corners():
            for i in range(4):
                best = min(best, point_segment(p, corners[i], corners[(i + 1) % 4]))
    return best


def _point_segment_m(p: tuple[float, float], q: tuple[float, float], r: tuple[float, float]) -> float:
    dx, dy = r[0] - q[0], r[1] - q[1]
    if dx == 0.0 and dy == 0.0:
        return math.hypot(p[0] - q[0], p[1] - q[1])
    t = max(0.0, min(1.0, ((p[0] - q[0]) * dx + (p[1] - q[1]) * dy) / (dx * dx + dy * dy)))
    return math.hypot(p[0] - q[0] - t * dx, p[1] - q[1] - t * dy)


def _polygon_gap_m(
    first: Sequence[Sequence[tuple[float, float]]], second: Sequence[Sequence[tuple[float, float]]]
) -> float:
    """The least distance between the boundaries of two sets of polygons that do not overlap."""
    best = math.inf
    for one, other in ((first, second), (second, first)):
        for polygon in one:
            for other_polygon in other:
                count = len(other_polygon)
                for p in polygon:
                    for i in range(count):
                        best = min(best, _point_segment_m(p, other_polygon[i], other_polygon[(i + 1) % count]))
    return best


def radius_of(footprint: Footprint) -> float:
    """The farthest a footprint reaches from its origin."""
    if isinstance(footprint, Rect):
        return math.hypot(footprint.half_x_m, footprint.half_y_m)
    return max(math.hypot(x, y) for piece in footprint.pieces for x, y in piece)
