"""The prism: a flat part whose top face is any simple polygon, convex or not (an L, a fresco piece).

Its frame is the outline's area centroid, its x axis the outline's x axis as written, z up from
the table. The pads grasp it at antipodal pairs of edges (parallel or nearly so, within the pads'
friction cone, the width within the stroke), nearest the centroid first; a push meets the part's
back-most points along the push. Everything is in metres and radians; the outline is stored
counter-clockwise whatever the winding it was written in.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from bt_arrange.errors import PlanError
from bt_arrange.geometry import FloatArray
from bt_arrange.shapes.base import MAX_HEIGHT_M, MIN_EDGE_M, Grasp, PushedFace
from bt_arrange.shapes.gripper import Gripper

#: A side between two corners shorter than this is one the camera cannot measure.
MIN_PERCEIVED_EDGE_M = 0.010
#: A turn of the outline under this at a vertex is no corner: a short edge there does not matter.
CORNER_TURN_RAD = math.radians(10.0)
#: Two outlines whose vertices lie this close after a turn are the same: the turn is a symmetry.
SYMMETRY_TOLERANCE_M = 0.0005
#: The pads hold where edges face each other within this angle of antipodal (a cone of friction 0.3,
#: well inside the pads' measured 1.2 on wood, so a part never slips out turning).
ANTIPODAL_HALF_ANGLE_RAD = math.atan(0.3)
#: A grasp needs the two edges to overlap this much along the pads (a third of a 22 mm pad).
MIN_GRASP_OVERLAP_M = 0.008
#: Points of the outline within this of the back-most line along a push are what the pads meet.
PUSH_CONTACT_BAND_M = 0.001
#: The least opening of the fingers for pushing an irregular part, nearly closed: both pads land on
#: the edge a square push meets (``Prism.named_pushes`` opens them wider where the edge allows).
PRISM_PUSH_OPENING_M = 0.004
#: A square push needs an edge this long: the pads' span (two pads beside the opening) and 2 mm.
MIN_PUSHED_EDGE_M = 0.022


def _signed_area_m2(points: FloatArray) -> float:
    x, y = points[:, 0], points[:, 1]
    return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


def _centroid_m(points: FloatArray) -> FloatArray:
    x, y = points[:, 0], points[:, 1]
    cross = x * np.roll(y, -1) - np.roll(x, -1) * y
    area = 0.5 * float(np.sum(cross))
    cx = float(np.sum((x + np.roll(x, -1)) * cross)) / (6.0 * area)
    cy = float(np.sum((y + np.roll(y, -1)) * cross)) / (6.0 * area)
    return np.array([cx, cy])


def _segments_cross(p1: FloatArray, p2: FloatArray, q1: FloatArray, q2: FloatArray) -> bool:
    """True when the closed segments p1-p2 and q1-q2 meet (touching counts)."""

    def orient(a: FloatArray, b: FloatArray, c: FloatArray) -> float:
        return float((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]))

    def on(a: FloatArray, b: FloatArray, c: FloatArray) -> bool:
        return min(a[0], b[0]) - 1e-12 <= c[0] <= max(a[0], b[0]) + 1e-12 and (
            min(a[1], b[1]) - 1e-12 <= c[1] <= max(a[1], b[1]) + 1e-12
        )

    d1, d2 = orient(q1, q2, p1), orient(q1, q2, p2)
    d3, d4 = orient(p1, p2, q1), orient(p1, p2, q2)
    if ((d1 > 0 > d2) or (d1 < 0 < d2)) and ((d3 > 0 > d4) or (d3 < 0 < d4)):
        return True
    return any(
        abs(d) <= 1e-18 and on(a, b, c)
        for d, a, b, c in ((d1, q1, q2, p1), (d2, q1, q2, p2), (d3, p1, p2, q1), (d4, p1, p2, q2))
    )


def told_apart(first: object, second: object) -> bool:
    """True when the camera tells parts of these two shapes apart by outline alone: two prisms not congruent.

    Congruent outlines (the same vertices up to a turn and a mirror, within half a millimetre)
    register onto each other, so parts of one colour must differ in outline to share it.
    """
    if not (isinstance(first, Prism) and isinstance(second, Prism)):
        return False
    a, b = first.outline_m, second.outline_m
    if len(a) != len(b) or abs(first.area_m2 - second.area_m2) > 0.01 * max(first.area_m2, second.area_m2):
        return True

    def sides(points: FloatArray) -> FloatArray:
        return np.sort(np.hypot(*(np.roll(points, -1, axis=0) - points).T))

    return not np.allclose(sides(a), sides(b), atol=SYMMETRY_TOLERANCE_M)


def outline_problem(points: Sequence[Sequence[float]]) -> str | None:
    """Why ``points`` (N x 2, metres) is no simple polygon: too few points, degenerate, self-intersecting."""
    array = np.asarray(points, dtype=float)
    if array.ndim != 2 or array.shape[1] != 2 or len(array) < 3:
        return f"an outline needs at least three points [x, y], got {len(array) if array.ndim == 2 else 0}"
    if not np.all(np.isfinite(array)):
        return "an outline's points must be finite numbers"
    edges = np.roll(array, -1, axis=0) - array
    lengths = np.hypot(edges[:, 0], edges[:, 1])
    if np.any(lengths < 1e-6):
        index = int(np.argmin(lengths))
        return f"the outline repeats point {index + 1} (an edge of no length)"
    # Points on one line first: a symmetric bow tie also has no signed area, but it crosses itself.
    if np.linalg.svd(array - array.mean(axis=0), compute_uv=False)[1] < 1e-6:
        return "the outline encloses no area (its points lie on a line)"
    count = len(array)
    for i in range(count):
        for j in range(i + 1, count):
            if j == i + 1 or (i == 0 and j == count - 1):
                continue  # neighbours share a point
            if _segments_cross(array[i], array[(i + 1) % count], array[j], array[(j + 1) % count]):
                return f"the outline crosses itself (edges {i + 1} and {j + 1} meet)"
    if abs(_signed_area_m2(array)) < 1e-8:
        return "the outline encloses no area"
    return None


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
class SquarePush:
    """A push that meets one edge squarely.

    Its ``heading_rad`` in the part's frame (the edge's inward normal), how far behind the centroid
    the edge lies (``back_m``), the edge's length and index, and the fingers' opening.
    """

    heading_rad: float
    back_m: float
    edge_m: float
    edge: int
    #: The fingers' opening for this push (``Prism.named_pushes``).
    opening_m: float = PRISM_PUSH_OPENING_M


@dataclass(frozen=True)
class Prism:
    """A flat part: the top face ``outline_m`` (counter-clockwise about the area centroid) extruded ``height_m``.

    Make one with :meth:`from_outline` from points in any frame and either winding.
    """

    outline: tuple[tuple[float, float], ...]
    height: float

    @classmethod
    def from_outline(cls, points_m: Sequence[Sequence[float]], height_m: float) -> Prism:
        """The prism of an outline written in any frame and winding (metres); a ``PlanError`` if it is no polygon."""
        problem = outline_problem(points_m)
        if problem is not None:
            raise PlanError(problem)
        if not (isinstance(height_m, (int, float)) and math.isfinite(height_m) and height_m > 0):
            raise PlanError(f"a prism's height must be a positive number, got {height_m!r}")
        array = np.asarray(points_m, dtype=float)
        if _signed_area_m2(array) < 0:
            array = array[::-1]
        centred = array - _centroid_m(array)
        return cls(tuple((float(x), float(y)) for x, y in centred), float(height_m))

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
    def area_m2(self) -> float:
        """The top face's area."""
        return _signed_area_m2(self.outline_m)

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
        return _grasps(self, gripper)

    def _grasps(self, gripper: Gripper) -> tuple[Grasp, ...]:
        found: dict[tuple[float, float], tuple[float, float, Grasp]] = {}
        half_pad = gripper.pad_width_m / 2
        height_m = max(self.height / 2, gripper.lowest_tcp_m)
        for closing in self._closing_axes():
            along = np.array([-closing[1], closing[0]])
            grasp = self._grasp_along(closing, along, half_pad, height_m, gripper.max_grasp_width_m)
            if grasp is None:
                continue
            key = (round(grasp.yaw_offset_rad, 6), round(grasp.centre_m[0], 4))
            distance = float(np.hypot(*grasp.centre_m))
            if key not in found or distance < found[key][0]:
                found[key] = (distance, grasp.width_m, grasp)
        ordered = sorted(found.values(), key=lambda item: (round(item[0], 6), item[1]))
        return tuple(grasp for _, _, grasp in ordered)

    def _closing_axes(self) -> list[FloatArray]:
        """Unit closing directions, one per half-turn class: edge normals and antipodal bisectors."""
        points = self.outline_m
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
        self, closing: FloatArray, along: FloatArray, half_pad: float, height_m: float, max_width_m: float
    ) -> Grasp | None:
        """The grasp closing along ``closing`` nearest the centroid, or None."""
        points = self.outline_m
        t_values = points @ along
        low, high = float(np.min(t_values)), float(np.max(t_values))
        if high - low < MIN_GRASP_OVERLAP_M:
            return None
        step = 0.0005
        centres = np.arange(low, high + step / 2, step)
        for centre_t in sorted((float(t) for t in centres), key=lambda t: (abs(t), t)):
            band = half_pad
            slab = self._slab(closing, along, centre_t, band)
            if slab is None:
                continue
            top, bottom = float(np.max(slab[:, 0])), float(np.min(slab[:, 0]))
            if top - bottom > max_width_m:
                continue
            wider = self._slab(closing, along, centre_t, band + 0.003)
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
            axis = (
                "x" if abs(math.sin(yaw)) < 1e-9 else "y" if abs(math.cos(yaw)) < 1e-9 else f"{math.degrees(yaw):.1f}"
            )
            return Grasp(axis, yaw, top - bottom, height_m, (float(centre[0]), float(centre[1])))
        return None

    def _slab(self, closing: FloatArray, along: FloatArray, centre_t: float, half_m: float) -> FloatArray | None:
        """The outline's points (as ``[across, t]``) within ``|t - centre_t| <= half_m``, cut where its edges cross."""
        points = self.outline_m
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
        """The top face split into convex polygons (counter-clockwise), for engines whose bodies are convex hulls.

        Ear clipping gives triangles; neighbouring pieces are then merged while the union stays
        convex (Hertel and Mehlhorn), so a convex outline is one piece and an L two.
        """
        points = self.outline_m
        pieces = [list(triangle) for triangle in _ear_clip(points)]
        merged = True
        while merged:
            merged = False
            for i in range(len(pieces)):
                for j in range(i + 1, len(pieces)):
                    union = _merge_if_convex(points, pieces[i], pieces[j])
                    if union is not None:
                        pieces[i] = union
                        del pieces[j]
                        merged = True
                        break
                if merged:
                    break
        return [points[piece] for piece in pieces]

    def problems(self, gripper: Gripper) -> list[str]:
        """Too thin or too tall for the pads, a short edge at a corner, no grasp the gripper can take."""
        found = self.size_problems()
        if not self.grasps(gripper):
            found.append(
                f"no two edges the {gripper.name.split()[-1]} can close on (facing each other, overlapping "
                f"{MIN_GRASP_OVERLAP_M * 1000:.0f} mm or more, at most {gripper.max_grasp_width_m * 1000:.0f} mm apart)"
            )
        return found

    def size_problems(self) -> list[str]:
        """Too thin or too tall for the pads, a short edge at a corner: the checks that need no grasp search."""
        found = []
        if self.height < MIN_EDGE_M:
            found.append(f"{self.height * 1000:g} mm tall, thinner than the pads' {MIN_EDGE_M * 1000:.0f} mm")
        if self.height > MAX_HEIGHT_M:
            found.append(f"{self.height * 1000:g} mm tall, taller than {MAX_HEIGHT_M * 1000:.0f} mm")
        points = self.outline_m
        count = len(points)
        for k in range(count):
            before, here, after = points[k - 1], points[k], points[(k + 1) % count]
            length = float(np.hypot(*(after - here)))
            if length >= MIN_PERCEIVED_EDGE_M:
                continue
            turn_in = _turn_rad(before, here, after)
            turn_out = _turn_rad(here, after, points[(k + 2) % count])
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


@functools.lru_cache(maxsize=1024)
def _grasps(prism: Prism, gripper: Gripper) -> tuple[Grasp, ...]:
    """``Prism.grasps``, kept per prism and gripper (both frozen): every step asks, and the search scans the outline."""
    return prism._grasps(gripper)


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


def _cross_z(o: FloatArray, a: FloatArray, b: FloatArray) -> float:
    return float((a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]))


def _ear_clip(points: FloatArray) -> list[tuple[int, int, int]]:
    """Triangles (vertex indices, counter-clockwise) covering a simple counter-clockwise polygon."""
    remaining = list(range(len(points)))
    triangles: list[tuple[int, int, int]] = []
    while len(remaining) > 3:
        for k in range(len(remaining)):
            i, j, n = remaining[k - 1], remaining[k], remaining[(k + 1) % len(remaining)]
            a, b, c = points[i], points[j], points[n]
            if _cross_z(a, b, c) <= 1e-14:
                continue  # a reflex or flat corner is no ear
            inside = any(
                _cross_z(a, b, points[m]) >= 0 and _cross_z(b, c, points[m]) >= 0 and _cross_z(c, a, points[m]) >= 0
                for m in remaining
                if m not in (i, j, n)
            )
            if not inside:
                triangles.append((i, j, n))
                del remaining[k]
                break
        else:  # numerically degenerate: fan out what is left
            break
    for k in range(1, len(remaining) - 1):
        triangles.append((remaining[0], remaining[k], remaining[k + 1]))
    return triangles


def _merge_if_convex(points: FloatArray, first: list[int], second: list[int]) -> list[int] | None:
    """The union of two convex pieces sharing an edge (vertex indices), if it is convex; else None."""
    for a in range(len(first)):
        u, v = first[a], first[(a + 1) % len(first)]
        if v in second and second[(second.index(v) + 1) % len(second)] == u:
            start = second.index(u)
            rest = [second[(start + k) % len(second)] for k in range(1, len(second) - 1)]
            union = first[: a + 1] + rest + first[a + 1 :]
            return union if _is_convex(points[union]) else None
    return None


def _is_convex(points: FloatArray) -> bool:
    count = len(points)
    return all(_cross_z(points[k - 1], points[k], points[(k + 1) % count]) >= -1e-14 for k in range(count))


def _turn_rad(before: FloatArray, here: FloatArray, after: FloatArray) -> float:
    """How far the outline turns at ``here`` (signed, radians)."""
    a, b = here - before, after - here
    return math.atan2(float(a[0] * b[1] - a[1] * b[0]), float(a @ b))
