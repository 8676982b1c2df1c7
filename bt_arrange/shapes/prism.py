"""The prism, *the* shape of a part: a flat part whose top face is any simple polygon (a box, an L, a fresco piece).

Every part is a :class:`Prism`. A box, the paper's cube among them, is the prism :class:`Cuboid`
(made by :meth:`Prism.box`, or by :meth:`Prism.from_outline` of an outline that is a rectangle
along its axes): it declares the trait ``rectangular``, which the steps with a faster path for
boxes ask (the corner detector, the tilt check, the depth-only estimator, the layout's
rectangles), and answers the protocol with the box arithmetic the paper's results were measured
with. A step never asks which class a shape is.

A prism's frame is the outline's area centroid, its x axis the outline's x axis as written, z up from
the table. The pads grasp it at antipodal pairs of edges (parallel or nearly so, within the pads'
friction cone, the width within the stroke), nearest the centroid first; a push meets the part's
back-most points along the push. Everything is in metres and radians; the outline is stored
counter-clockwise whatever the winding it was written in.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import ClassVar

import numpy as np

from bt_arrange.errors import PlanError
from bt_arrange.geometry import FloatArray, fold_yaw
from bt_arrange.shapes.antipodal import MIN_GRASP_OVERLAP_M, antipodal_grasps
from bt_arrange.shapes.base import MAX_HEIGHT_M, MIN_EDGE_M, PRISM_PUSH_OPENING_M, Grasp, PushedFace, Shape, SquarePush
from bt_arrange.shapes.gripper import Gripper
from bt_arrange.shapes.polygon import centroid_m, convex_pieces, outline_problem, signed_area_m2, turn_rad
from bt_arrange.shapes.yaw_feature import yaw_feature_m

#: A side between two corners shorter than this is one the camera cannot measure.
MIN_PERCEIVED_EDGE_M = 0.010
#: A turn of the outline under this at a vertex is no corner: a short edge there does not matter.
CORNER_TURN_RAD = math.radians(10.0)
#: Two outlines whose vertices lie this close after a turn are the same: the turn is a symmetry.
SYMMETRY_TOLERANCE_M = 0.0005
#: The smallest feature that tells a part's yaws apart to the top camera: an outline that, turned to
#: another yaw that is no symmetry, comes within this of itself everywhere (``yaw_feature_m``) is refused.
#: The sim camera sees 0.47 mm a pixel at the table; its sub-pixel edges told a 0.2 mm feature apart on
#: every synthetic frame tried, and not 0.1 mm (docs/irregular.md).
MIN_YAW_FEATURE_M = 0.0003
#: Points of the outline within this of the back-most line along a push are what the pads meet.
PUSH_CONTACT_BAND_M = 0.001
#: A square push needs an edge this long: the pads' span (two pads beside the opening) and 2 mm.
MIN_PUSHED_EDGE_M = 0.022


def told_apart(first: Shape, second: Shape) -> bool:
    """True when the camera tells parts of these two shapes apart by outline alone: two prisms not congruent.

    Congruent outlines (the same vertices up to a turn and a mirror, within half a millimetre)
    register onto each other, so parts of one colour must differ in outline to share it.
    """
    if first.rectangular or second.rectangular:  # boxes are found by their corners, not their outlines
        return False
    a, b = first.outline_m, second.outline_m
    if len(a) != len(b) or abs(first.area_m2 - second.area_m2) > 0.01 * max(first.area_m2, second.area_m2):
        return True

    def sides(points: FloatArray) -> FloatArray:
        return np.sort(np.hypot(*(np.roll(points, -1, axis=0) - points).T))

    return not np.allclose(sides(a), sides(b), atol=SYMMETRY_TOLERANCE_M)


def push_name(heading_rad: float) -> str:
    """A square push's name: its heading in the part's frame in degrees, ``"@-54.0"``."""
    return f"@{math.degrees(heading_rad):.1f}"


def push_heading_rad(name: str) -> float | None:
    """The heading (part frame, radians) a push name says, or None when it is no square push's name."""
    if not name.startswith("@"):
        return None
    try:
        return math.radians(float(name[1:]))
    except ValueError:
        return None


@dataclass(frozen=True)
class Prism:
    """A flat part: the top face ``outline_m`` (counter-clockwise about the area centroid) extruded ``height_m``.

    Make one with :meth:`from_outline` from points in any frame and either winding.
    """

    outline: tuple[tuple[float, float], ...]
    height: float

    #: The top face is a rectangle along the part's own axes (a :class:`Cuboid`): its steps may take
    #: the boxes' faster paths (corners, tilt, depth-only grasps, the layout's rectangles).
    rectangular: ClassVar[bool] = False

    @classmethod
    def from_outline(cls, points_m: Sequence[Sequence[float]], height_m: float) -> Prism:
        """The prism of an outline written in any frame and winding (metres); a ``PlanError`` if it is no polygon.

        An outline that is a rectangle along its own x and y axes is the box of that size (a
        :class:`Cuboid`, centred on the rectangle): the same part however it was written.
        """
        problem = outline_problem(points_m)
        if problem is not None:
            raise PlanError(problem)
        if not (isinstance(height_m, (int, float)) and math.isfinite(height_m) and height_m > 0):
            raise PlanError(f"a prism's height must be a positive number, got {height_m!r}")
        array = np.asarray(points_m, dtype=float)
        box = _box_size_m(array)
        if box is not None:
            return Cuboid((box[0], box[1], float(height_m)))
        if signed_area_m2(array) < 0:
            array = array[::-1]
        centred = array - centroid_m(array)
        return cls(tuple((float(x), float(y)) for x, y in centred), float(height_m))

    @staticmethod
    def box(x_m: float, y_m: float, z_m: float) -> Cuboid:
        """The box prism of edges ``x_m`` by ``y_m`` on the table, ``z_m`` tall (the paper's cube: all 0.05)."""
        return Cuboid((float(x_m), float(y_m), float(z_m)))

    # -- the Shape protocol ---------------------------------------------------------------------

    @property
    def height_m(self) -> float:
        """The top face's height above the table."""
        return self.height

    @property
    def outline_m(self) -> FloatArray:
        """The top face, counter-clockwise, in the part's frame (origin at its area centroid)."""
        return np.array(self.outline)

    @property
    def extent_m(self) -> tuple[float, float]:
        """The smallest box centred on the centroid, axes along the part's, that holds the top face."""
        points = self.outline_m
        return 2.0 * float(np.max(np.abs(points[:, 0]))), 2.0 * float(np.max(np.abs(points[:, 1])))

    @property
    def size_m(self) -> tuple[float, float, float]:
        """The part's bounding box: ``extent_m`` and the height (a box's edges)."""
        x_m, y_m = self.extent_m
        return float(x_m), float(y_m), float(self.height)

    @property
    def square_top(self) -> bool:
        """True for a square top face along the part's axes (a box's trait; a prism's outline is registered)."""
        return False

    @property
    def is_cube(self) -> bool:
        """True for a cube (a box's trait)."""
        return False

    @property
    def area_m2(self) -> float:
        """The top face's area."""
        return signed_area_m2(self.outline_m)

    def support_m(self, direction: FloatArray) -> float:
        """How far the part reaches from its mid-height centroid along a unit ``direction`` (own frame, 3-vector)."""
        along = np.asarray(direction, dtype=float)
        outline = self.outline_m
        top = outline @ along[:2]
        return float(np.max(top)) + abs(float(along[2])) * self.height / 2

    @property
    def symmetry_rad(self) -> float:
        """The smallest turn about the centroid that maps the outline onto itself; 2 pi for none."""
        points = self.outline_m
        count = len(points)
        for folds in range(count, 1, -1):
            if count % folds:
                continue
            turn = 2.0 * math.pi / folds
            c, s = math.cos(turn), math.sin(turn)
            turned = points @ np.array([[c, s], [-s, c]])
            step = count // folds
            if np.allclose(np.roll(points, -step, axis=0), turned, atol=SYMMETRY_TOLERANCE_M):
                return turn
        return 2.0 * math.pi

    @property
    def sweep_radius_m(self) -> float:
        """The farthest vertex from the centroid."""
        return float(np.max(np.hypot(*self.outline_m.T)))

    def grasps(self, gripper: Gripper) -> tuple[Grasp, ...]:
        """Where the pads can close on the part, the grasp nearest the centroid first.

        The closing axes tried are the edges' normals and the bisectors of edges facing each other
        within ``ANTIPODAL_HALF_ANGLE_RAD``. Along each, the pads (their width across it) stand at
        the place nearest the centroid where both meet a local extreme of the outline (an edge or a
        corner), their contacts face each other across the part (an edge against an edge overlapping
        ``MIN_GRASP_OVERLAP_M``, or a corner within an edge's span), and the part is no wider there
        than the gripper closes across.
        """
        return antipodal_grasps(self.outline, self.height, gripper)

    def pushed_face(self, heading_rad: float, yaw_rad: float) -> PushedFace:
        """What a push along ``heading_rad`` meets on the part turned to ``yaw_rad``.

        ``depth_m`` is twice the distance from the centroid back to the outline's back-most point
        along the push; ``width_m`` and ``leading_width_m`` the span, across the push, of the points
        within ``PUSH_CONTACT_BAND_M`` of that back-most line (0 where a corner leads).
        """
        relative = heading_rad - yaw_rad
        forward = np.array([math.cos(relative), math.sin(relative)])
        across = np.array([-forward[1], forward[0]])
        points = self.outline_m
        along = points @ forward
        back = float(np.min(along))
        contact = points[along <= back + PUSH_CONTACT_BAND_M] @ across
        width = float(np.max(contact) - np.min(contact)) if len(contact) > 1 else 0.0
        return PushedFace(width, -2.0 * back, width)

    def back_within_m(self, heading_rad: float, yaw_rad: float, half_span_m: float) -> float:
        """How far back from the centroid, along a push, the outline reaches within ``half_span_m`` of the push's line.

        Pads ``2 half_span_m`` wide, centred on the line through the centroid, first touch the part
        there: a corner that leads beside the pads (a triangle's) is not what they meet.
        """
        relative = heading_rad - yaw_rad
        forward = np.array([math.cos(relative), math.sin(relative)])
        across = np.array([-forward[1], forward[0]])
        points = self.outline_m
        along, side = points @ forward, points @ across
        reach = [float(-a) for a, c in zip(along, side, strict=True) if abs(c) <= half_span_m]
        count = len(points)
        for k in range(count):
            a0, a1 = along[k], along[(k + 1) % count]
            c0, c1 = side[k], side[(k + 1) % count]
            for bound in (-half_span_m, half_span_m):
                if (c0 - bound) * (c1 - bound) < 0:
                    s = (bound - c0) / (c1 - c0)
                    reach.append(float(-(a0 + s * (a1 - a0))))
        return max(reach) if reach else float(-np.min(along))

    def push_contact_m(self, heading_rad: float, yaw_rad: float) -> tuple[float, float]:
        """The span (low, high) across the push, from the line through the centroid, of what the pads meet."""
        relative = heading_rad - yaw_rad
        forward = np.array([math.cos(relative), math.sin(relative)])
        across = np.array([-forward[1], forward[0]])
        points = self.outline_m
        along = points @ forward
        contact = points[along <= float(np.min(along)) + PUSH_CONTACT_BAND_M] @ across
        return float(np.min(contact)), float(np.max(contact))

    def square_pushes(self, half_span_m: float, min_edge_m: float = 0.0) -> tuple[SquarePush, ...]:
        """The pushes that meet an edge squarely, through the centroid, longest edge first.

        A push along an edge's inward normal, its line through the centroid, meets that edge
        squarely when the pads (``half_span_m`` each side of the line) land on it and nothing of
        the outline lies further back within their span. Both pads then touch, so the push
        neither turns the part nor slides it along the pads: it squares that edge to the push
        (a part turned a little is turned back). ``min_edge_m`` leaves out shorter edges.
        """
        points = self.outline_m
        count = len(points)
        found: list[SquarePush] = []
        for k in range(count):
            a, b = points[k], points[(k + 1) % count]
            edge = b - a
            length = float(np.hypot(*edge))
            if length < max(min_edge_m, 2 * half_span_m):
                continue
            tangent = edge / length
            inward = np.array([-tangent[1], tangent[0]])  # counter-clockwise: the inside is on the left
            # Where the line through the centroid along the normal crosses the edge, along it.
            along_edge = float((-a) @ tangent)
            if not half_span_m <= along_edge <= length - half_span_m:
                continue
            heading = math.atan2(float(inward[1]), float(inward[0]))
            back_m = float(-(a @ inward))  # the edge lies this far behind the centroid along the push
            if back_m <= 0 or abs(self.back_within_m(heading, 0.0, half_span_m) - back_m) > PUSH_CONTACT_BAND_M:
                continue  # something else of the outline meets the pads first
            found.append(SquarePush(heading, back_m, length, k))
        return tuple(sorted(found, key=lambda push: -push.edge_m))

    def named_pushes(self, gripper: Gripper) -> dict[str, SquarePush]:
        """The square pushes of this part, by name, each with the widest opening its edge takes.

        The fingers open as wide as keeps both pads on the edge and each finger
        (``finger_depth_m`` beyond its pad, ``neighbour_clearance_m`` to spare) within the edge's
        ends, so a neighbour in line with the edge is never touched; at least
        ``PRISM_PUSH_OPENING_M``. The wider the pads stand, the harder a turned part is squared.
        A push's name is its heading in the part's frame, ``"@123.4"`` (degrees): the layout lists
        the ones a neighbour leaves free, and Push makes them.
        """
        least_half_span_m = PRISM_PUSH_OPENING_M / 2 + gripper.pad_thickness_m
        points = self.outline_m
        count = len(points)
        named: dict[str, SquarePush] = {}
        for push in self.square_pushes(least_half_span_m, MIN_PUSHED_EDGE_M):
            a, b = points[push.edge], points[(push.edge + 1) % count]
            tangent = (b - a) / push.edge_m
            along_edge = float((-a) @ tangent)
            room_m = min(along_edge, push.edge_m - along_edge)
            reach_m = gripper.finger_depth_m + gripper.neighbour_clearance_m
            opening_m = min(gripper.stroke_m, max(PRISM_PUSH_OPENING_M, 2 * (room_m - reach_m)))
            while opening_m > PRISM_PUSH_OPENING_M:
                half_span_m = opening_m / 2 + gripper.pad_thickness_m
                if abs(self.back_within_m(push.heading_rad, 0.0, half_span_m) - push.back_m) <= PUSH_CONTACT_BAND_M:
                    break
                opening_m = max(PRISM_PUSH_OPENING_M, opening_m - 0.002)  # the outline rises beside the edge
            named[push_name(push.heading_rad)] = replace(push, opening_m=opening_m)
        return named

    def convex_pieces(self) -> list[FloatArray]:
        """The top face split into convex polygons (counter-clockwise): engines' bodies, the layout's footprints."""
        return convex_pieces(self.outline_m)

    def problems(self, gripper: Gripper) -> list[str]:
        """Too thin or too tall for the pads, a short edge at a corner, no grasp the gripper can take."""
        found = self.size_problems()
        if not self.grasps(gripper):
            found.append(
                f"no two edges the {gripper.name.split()[-1]} can close on (facing each other, overlapping "
                f"{MIN_GRASP_OVERLAP_M * 1000:.0f} mm or more, at most {gripper.max_grasp_width_m * 1000:.0f} mm apart)"
            )
        if not found:
            found.extend(self.yaw_problems())
        return found

    def yaw_problems(self) -> list[str]:
        """An outline whose yaws the camera cannot tell apart: nearly, but not quite, symmetric.

        A truly symmetric outline (its vertices within 0.5 mm of themselves turned) is fine: every
        equivalent yaw is as good. One that comes back within ``MIN_YAW_FEATURE_M`` of itself under
        another turn is not, for the camera would take one yaw for the other.
        """
        feature_m, turn = yaw_feature_m(self.outline_m, self.symmetry_rad, refine_below_m=MIN_YAW_FEATURE_M)
        if feature_m >= MIN_YAW_FEATURE_M - 1e-9:  # a written 0.6 mm is 0.6 mm
            return []
        return [
            f"the outline turned by {math.degrees(turn):.0f} deg comes within {feature_m * 1000:.2f} mm of itself: the "
            f"camera tells yaws apart by a feature of at least {MIN_YAW_FEATURE_M * 1000:.1f} mm (make the outline "
            "differ more under that turn, or make it symmetric to within 0.5 mm)"
        ]

    def size_problems(self) -> list[str]:
        """Too thin or too tall for the pads, a short edge at a corner: the checks that need no grasp search."""
        found = []
        if self.height < MIN_EDGE_M:
            found.append(f"{self.height * 1000:g} mm tall, thinner than the pads' {MIN_EDGE_M * 1000:.0f} mm")
        if self.height > MAX_HEIGHT_M:
            found.append(f"{self.height * 1000:g} mm tall, taller than {MAX_HEIGHT_M * 1000:.0f} mm")
        points = self.outline_m
        count = len(points)
        steps = np.concatenate((points[1:], points[:1])) - points
        lengths = np.hypot(steps[:, 0], steps[:, 1]).tolist()  # edge k runs from corner k to k + 1
        for k in np.flatnonzero(np.array(lengths) < MIN_PERCEIVED_EDGE_M).tolist():
            before, here, after = points[k - 1], points[k], points[(k + 1) % count]
            length = lengths[k]
            turn_in = turn_rad(before, here, after)
            turn_out = turn_rad(here, after, points[(k + 2) % count])
            if min(abs(turn_in), abs(turn_out)) >= CORNER_TURN_RAD:  # a side between two corners
                found.append(
                    f"edge {k + 1} is {length * 1000:.1f} mm long, under the {MIN_PERCEIVED_EDGE_M * 1000:.0f} mm "
                    "the camera needs to measure a corner"
                )
                break
        return found

    def describe(self) -> str:
        """The outline in a few words: its vertices, extent and height in millimetres."""
        x_m, y_m = self.extent_m
        size = f"{x_m * 1000:.0f} x {y_m * 1000:.0f} mm"
        return f"{len(self.outline)}-sided outline within {size}, {self.height * 1000:g} mm tall"


#: Corners of a written rectangle within this of the box's (metres) make the outline that box.
BOX_TOLERANCE_M = 1e-9


def _box_size_m(points: FloatArray) -> tuple[float, float] | None:
    """(x, y) of the box an outline is, when it is a rectangle along its own axes; else None."""
    if len(points) != 4:
        return None
    low, high = points.min(axis=0), points.max(axis=0)
    corners = {(float(x), float(y)) for x in (low[0], high[0]) for y in (low[1], high[1])}
    if (
        not all(
            any(abs(px - cx) <= BOX_TOLERANCE_M and abs(py - cy) <= BOX_TOLERANCE_M for cx, cy in corners)
            for px, py in points
        )
        or len({(round(px / BOX_TOLERANCE_M), round(py / BOX_TOLERANCE_M)) for px, py in points}) != 4
    ):
        return None
    return _edge_m(float(low[0]), float(high[0])), _edge_m(float(low[1]), float(high[1]))


def _edge_m(low: float, high: float) -> float:
    """A box's edge from its outline's extremes: exact when written about its centre, else to 15 digits.

    An offset rectangle's edges come out of the subtraction an ulp off (0.18 - 0.10 is
    0.07999999999999999); 15 significant digits take that back and keep any written figure.
    """
    if low == -high:
        return high - low
    return float(f"{high - low:.15g}")


#: Two edges closer than this (metres) make a square top.
SQUARE_TOLERANCE_M = 0.0005


class Cuboid(Prism):
    """The box prism: ``x`` and ``y`` across its top face, ``z`` its height on the table (metres).

    ``Cuboid((x, y, z))`` or :meth:`Prism.box`. Its frame is the box's centre, axes along its
    edges; its outline the four corners counter-clockwise from ``(-x/2, -y/2)``. It declares the
    trait ``rectangular`` and answers with the box arithmetic: the pads close across the narrower
    side of the top face (either side of a square top) through the centre; a push meets the face
    square to its heading.
    """

    rectangular: ClassVar[bool] = True

    def __init__(self, size_m: tuple[float, float, float]) -> None:
        size = (float(size_m[0]), float(size_m[1]), float(size_m[2]))
        hx, hy = size[0] / 2, size[1] / 2
        object.__setattr__(self, "outline", ((-hx, -hy), (hx, -hy), (hx, hy), (-hx, hy)))
        object.__setattr__(self, "height", size[2])
        object.__setattr__(self, "_size_m", size)

    def __repr__(self) -> str:
        return f"Cuboid(size_m={self.size_m!r})"

    @property
    def size_m(self) -> tuple[float, float, float]:
        """The box's edges (x, y, z)."""
        size: tuple[float, float, float] = self.__dict__["_size_m"]
        return size

    def __reduce__(self) -> tuple[type[Cuboid], tuple[tuple[float, float, float]]]:
        return (Cuboid, (self.size_m,))

    @property
    def extent_m(self) -> tuple[float, float]:
        """The top face's edges (x, y)."""
        return self.size_m[0], self.size_m[1]

    @property
    def outline_m(self) -> FloatArray:
        """The top face's four corners, counter-clockwise from (-x/2, -y/2)."""
        hx, hy = self.size_m[0] / 2, self.size_m[1] / 2
        return np.array([[-hx, -hy], [hx, -hy], [hx, hy], [-hx, hy]])

    @property
    def area_m2(self) -> float:
        """The top face's area."""
        return self.size_m[0] * self.size_m[1]

    @property
    def square_top(self) -> bool:
        """True when the top face is a square (within 0.5 mm)."""
        return abs(self.size_m[0] - self.size_m[1]) < SQUARE_TOLERANCE_M

    @property
    def is_cube(self) -> bool:
        """True for a cube: a square top as tall as it is wide (within 0.5 mm)."""
        return self.square_top and abs(self.size_m[0] - self.size_m[2]) < SQUARE_TOLERANCE_M

    @property
    def symmetry_rad(self) -> float:
        """90 degrees for a square top, 180 otherwise."""
        return math.pi / 2 if self.square_top else math.pi

    def yaw_problems(self) -> list[str]:
        """A top nearly, but not quite, square: turned a quarter it comes within half the sides' difference."""
        if self.square_top:
            return []
        feature_m = abs(self.size_m[0] - self.size_m[1]) / 2
        if feature_m >= MIN_YAW_FEATURE_M - 1e-9:  # a written 0.6 mm is 0.6 mm
            return []
        return [
            f"size {self.describe()}: its top turned by 90 deg comes within {feature_m * 1000:.2f} mm of itself: the "
            f"camera tells yaws apart by a feature of at least {MIN_YAW_FEATURE_M * 1000:.1f} mm (make the sides "
            f"differ by {2 * MIN_YAW_FEATURE_M * 1000:.1f} mm or more, or by under {SQUARE_TOLERANCE_M * 1000:.1f} mm)"
        ]

    @property
    def sweep_radius_m(self) -> float:
        """Half the top face's diagonal."""
        return 0.5 * math.hypot(self.size_m[0], self.size_m[1])

    def support_m(self, direction: FloatArray) -> float:
        """How far the box reaches from its centre along a unit ``direction`` of its own frame (3-vector)."""
        half = [v / 2 for v in self.size_m]
        along = np.abs(np.asarray(direction, dtype=float))
        if half[0] == half[1] == half[2]:
            # A cube's in one product, the arithmetic the injectors were measured with.
            return half[0] * float(np.sum(along))
        return float(along @ np.array(half))

    def grasps(self, gripper: Gripper) -> tuple[Grasp, ...]:
        """Across the narrower side (``x`` first when they are equal), and across the other too on a square top.

        None when the narrower side is wider than the gripper closes across.
        """
        x_m, y_m, z_m = self.size_m
        height_m = max(z_m / 2, gripper.lowest_tcp_m)
        across_x = Grasp("x", 0.0, x_m, height_m)
        across_y = Grasp("y", math.pi / 2, y_m, height_m)
        preferred, other = (across_x, across_y) if x_m <= y_m else (across_y, across_x)
        if preferred.width_m > gripper.max_grasp_width_m:
            return ()
        return (preferred, other) if self.square_top else (preferred,)

    def pushed_face(self, heading_rad: float, yaw_rad: float) -> PushedFace:
        """The face square to the push, and its leading width at the part's turn from square."""
        relative = fold_yaw(heading_rad - yaw_rad, math.pi)
        along_x = abs(math.cos(relative)) >= abs(math.sin(relative))
        # Pushing along the part's x axis meets the face that spans its y edge.
        width_m, depth_m = (self.size_m[1], self.size_m[0]) if along_x else (self.size_m[0], self.size_m[1])
        turn_rad = abs(fold_yaw(heading_rad - yaw_rad, math.pi / 2))
        return PushedFace(width_m, depth_m, width_m * math.cos(turn_rad) - depth_m * math.sin(turn_rad))

    def convex_pieces(self) -> list[FloatArray]:
        """The top face, one convex piece."""
        return [self.outline_m]

    def problems(self, gripper: Gripper) -> list[str]:
        """An edge not positive or under 15 mm, taller than 100 mm, no side the gripper spans."""
        found = self.size_problems()
        if min(self.size_m) <= 0:
            return found
        size = self.describe()
        found.extend(self.yaw_problems())
        if not self.grasps(gripper):
            found.append(
                f"size {size} has no horizontal side the gripper can span (the {gripper.name.split()[-1]} closes "
                f"across at most {gripper.max_grasp_width_m * 1000:.0f} mm: its {gripper.stroke_m * 1000:.0f} mm "
                f"stroke less {gripper.grasp_clearance_m * 1000:.0f} mm of clearance)"
            )
        return found

    def size_problems(self) -> list[str]:
        """An edge not positive, under 15 mm, or taller than 100 mm: the checks that need no gripper."""
        size = self.describe()
        if min(self.size_m) <= 0:
            return [f"size {size} has an edge that is not positive"]
        found = []
        if min(self.size_m) < MIN_EDGE_M:
            found.append(
                f"size {size} has an edge under {MIN_EDGE_M * 1000:.0f} mm, too thin for the pads and the camera"
            )
        if self.size_m[2] > MAX_HEIGHT_M:
            found.append(f"{self.size_m[2] * 1000:g} mm tall, taller than {MAX_HEIGHT_M * 1000:.0f} mm")
        return found

    def describe(self) -> str:
        """The size in millimetres, e.g. ``80 x 40 x 40 mm``."""
        return " x ".join(f"{v * 1000:g}" for v in self.size_m) + " mm"
