"""The solver's view of one measured piece: a cleaned convex outline, its edges and corners, and its cell.

A piece as cut is its Voronoi cell moved in by half the gap along every fracture, not along the
slab's border. Pushed back out by half the gap along its fractures, a piece becomes its cell again,
and the cells tile the rectangle exactly, edge to edge (every fracture edge of one cell is an edge
of exactly one other, end to end): the search works on cells. Which edges are fractures is known
only once a piece is placed (an edge on the rectangle's side is the border), so a cell is built
for given border flags, one per edge.

Everything is in metres and radians; outlines are N x 2, counter-clockwise.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from bt_arrange.geometry import FloatArray
from bt_arrange.shapes.polygon import centroid_m, signed_area_m2

#: A measured edge shorter than this is taken for a camera artefact and merged into its neighbours.
MIN_EDGE_M = 0.0025
#: A corner that turns the outline by less than this is taken for a point on a straight edge.
MIN_CORNER_TURN_RAD = math.radians(2.0)
#: A vertex nearer than this to the chord of its neighbours is taken for a point on a straight edge.
COLLINEAR_M = 0.0002


def rotation(turn: float) -> FloatArray:
    """The 2 x 2 matrix turning a point by ``turn`` counter-clockwise."""
    c, s = math.cos(turn), math.sin(turn)
    return np.array([[c, -s], [s, c]])


def wrap(angle: float) -> float:
    """The angle in (-pi, pi]."""
    wrapped = math.atan2(math.sin(angle), math.cos(angle))
    return math.pi if wrapped <= -math.pi + 1e-15 else wrapped


def _line_meet(a: FloatArray, da: FloatArray, b: FloatArray, db: FloatArray) -> FloatArray | None:
    """Where the line through ``a`` along ``da`` meets the one through ``b`` along ``db`` (None if parallel)."""
    cross = float(da[0] * db[1] - da[1] * db[0])
    if abs(cross) < 1e-9:
        return None
    t = float((b - a)[0] * db[1] - (b - a)[1] * db[0]) / cross
    return a + t * da


def clean_outline(points: FloatArray) -> FloatArray:
    """The outline counter-clockwise, without near-collinear corners and with edges under ``MIN_EDGE_M`` merged.

    A short edge is replaced by the meeting point of the edges on either side of it (the corner the
    camera rounded off), or by its midpoint when those meet far away.
    """
    array = np.asarray(points, dtype=float).reshape(-1, 2)
    if signed_area_m2(array) < 0:
        array = array[::-1]
    changed = True
    while changed and len(array) > 3:
        changed = False
        count = len(array)
        for k in range(count):  # a corner that hardly turns
            before, here, after = array[k - 1], array[k], array[(k + 1) % count]
            chord = after - before
            offset = abs(float(chord[0] * (here - before)[1] - chord[1] * (here - before)[0])) / max(
                float(np.hypot(*chord)), 1e-12
            )
            turn = abs(
                math.atan2(
                    float((here - before)[0] * (after - here)[1] - (here - before)[1] * (after - here)[0]),
                    float((here - before) @ (after - here)),
                )
            )
            if offset < COLLINEAR_M or turn < MIN_CORNER_TURN_RAD:
                array = np.delete(array, k, axis=0)
                changed = True
                break
        if changed or len(array) <= 3:
            continue
        count = len(array)
        lengths = np.hypot(*(np.roll(array, -1, axis=0) - array).T)
        k = int(np.argmin(lengths))
        if lengths[k] < MIN_EDGE_M:
            before, a, b, after = array[k - 1], array[k], array[(k + 1) % count], array[(k + 2) % count]
            meet = _line_meet(before, a - before, after, b - after)
            middle = (a + b) / 2
            if meet is None or float(np.hypot(*(meet - middle))) > 2 * MIN_EDGE_M:
                meet = middle
            array[k] = meet
            array = np.delete(array, (k + 1) % count, axis=0)
            changed = True
    return array


@dataclass
class Shape:
    """One piece for the search: its cleaned outline about its own centroid, and what the search asks of it.

    ``points`` are the cleaned outline less ``centre`` (the measured outline's area centroid, table
    frame); ``angles[k]`` is the interior angle at corner k, ``directions[k]`` the unit direction of
    edge k (corner k to corner k+1), ``lengths[k]`` its length. ``samples`` are the colour samples'
    places (piece frame, about ``centre``) and ``colours`` their RGB, empty without colours.
    """

    index: int
    label: str
    centre: FloatArray
    points: FloatArray
    angles: FloatArray
    directions: FloatArray
    lengths: FloatArray
    area: float
    samples: FloatArray
    colours: FloatArray
    half_gap: float
    cell_lengths: FloatArray  # edge k's length in the cell, by border flags of edges k-1, k, k+1 (index 4a+2b+c)

    @property
    def count(self) -> int:
        """The number of corners (and edges)."""
        return len(self.points)

    def cell(self, border: Sequence[bool]) -> FloatArray:
        """The piece's cell (own frame): each edge not flagged border pushed out by half the gap."""
        count = self.count
        normals = np.stack([self.directions[:, 1], -self.directions[:, 0]], axis=1)
        offsets = np.where(np.asarray(border, dtype=bool), 0.0, self.half_gap)
        bases = self.points + normals * offsets[:, None]
        out = np.empty_like(self.points)
        for k in range(count):
            meet = _line_meet(bases[k - 1], self.directions[k - 1], bases[k], self.directions[k])
            out[k] = bases[k] if meet is None else meet
        return out

    def cell_corner(self, k: int, border_in: bool, border_out: bool) -> FloatArray:
        """Corner k of the cell when edge k-1 (in) and edge k (out) are border or not."""
        count = self.count
        d_in, d_out = self.directions[k - 1], self.directions[k]
        n_in, n_out = np.array([d_in[1], -d_in[0]]), np.array([d_out[1], -d_out[0]])
        base_in = self.points[k - 1] + n_in * (0.0 if border_in else self.half_gap)
        base_out = self.points[k] + n_out * (0.0 if border_out else self.half_gap)
        meet = _line_meet(base_in, d_in, base_out, d_out)
        return self.points[k % count] if meet is None else meet


def _cell_lengths(points: FloatArray, directions: FloatArray, half_gap: float) -> FloatArray:
    count = len(points)
    normals = np.stack([directions[:, 1], -directions[:, 0]], axis=1)
    table = np.zeros((count, 8))
    for k in range(count):
        for flags in range(8):
            flag_prev, flag_here, flag_next = bool(flags & 4), bool(flags & 2), bool(flags & 1)
            base_prev = points[k - 1] + normals[k - 1] * (0.0 if flag_prev else half_gap)
            base_here = points[k] + normals[k] * (0.0 if flag_here else half_gap)
            nxt = (k + 1) % count
            base_next = points[nxt] + normals[nxt] * (0.0 if flag_next else half_gap)
            start = _line_meet(base_prev, directions[k - 1], base_here, directions[k])
            end = _line_meet(base_here, directions[k], base_next, directions[nxt])
            if start is None or end is None:
                table[k, flags] = float(np.hypot(*(points[nxt] - points[k])))
            else:
                table[k, flags] = float((end - start) @ directions[k])
    return table


def make_shape(
    index: int,
    label: str,
    outline: FloatArray,
    half_gap: float,
    edge_colours: Sequence[FloatArray] | None,
) -> Shape:
    """The search's view of a measured outline (table frame) and its optional colour samples."""
    raw = np.asarray(outline, dtype=float).reshape(-1, 2)
    colours_by_edge = list(edge_colours) if edge_colours is not None else None
    if signed_area_m2(raw) < 0:
        raw = raw[::-1]
        if colours_by_edge is not None:  # edge k of the reversed outline is edge n-2-k reversed
            n = len(colours_by_edge)
            colours_by_edge = [np.asarray(colours_by_edge[(n - 2 - k) % n])[::-1] for k in range(n)]
    centre = centroid_m(raw)
    points = clean_outline(raw) - centre
    edges = np.roll(points, -1, axis=0) - points
    lengths = np.hypot(edges[:, 0], edges[:, 1])
    directions = edges / lengths[:, None]
    before = np.roll(directions, 1, axis=0)
    turns = np.arctan2(
        before[:, 0] * directions[:, 1] - before[:, 1] * directions[:, 0], np.sum(before * directions, 1)
    )
    angles = math.pi - turns
    samples, colours = _colour_samples(raw - centre, colours_by_edge)
    return Shape(
        index,
        label,
        centre,
        points,
        angles,
        directions,
        lengths,
        signed_area_m2(points),
        samples,
        colours,
        half_gap,
        _cell_lengths(points, directions, half_gap),
    )


def _colour_samples(outline: FloatArray, colours_by_edge: Sequence[FloatArray] | None) -> tuple[FloatArray, FloatArray]:
    """Each colour sample's place: spread evenly along its edge of the outline as measured."""
    if not colours_by_edge:
        return np.zeros((0, 2)), np.zeros((0, 3))
    places, values = [], []
    count = len(outline)
    for k, samples in enumerate(colours_by_edge[:count]):
        rgb = np.asarray(samples, dtype=float).reshape(-1, 3)
        if len(rgb) == 0:
            continue
        a, b = outline[k], outline[(k + 1) % count]
        fractions = (np.arange(len(rgb)) + 0.5) / len(rgb)
        places.append(a + fractions[:, None] * (b - a))
        values.append(rgb)
    if not places:
        return np.zeros((0, 2)), np.zeros((0, 3))
    return np.concatenate(places), np.concatenate(values)


def penetration(first: FloatArray, second: FloatArray) -> float:
    """How deep two convex polygons overlap: the least overlap of their projections over every edge normal.

    Zero or less when some edge separates them.
    """
    best = math.inf
    for polygon in (first, second):
        edges = np.roll(polygon, -1, axis=0) - polygon
        normals = np.stack([edges[:, 1], -edges[:, 0]], axis=1)
        normals /= np.hypot(normals[:, 0], normals[:, 1])[:, None]
        one = first @ normals.T
        two = second @ normals.T
        overlap = np.minimum(one.max(0), two.max(0)) - np.maximum(one.min(0), two.min(0))
        best = min(best, float(overlap.min()))
        if best <= 0:
            return best
    return best


__all__ = [
    "MIN_EDGE_M",
    "Shape",
    "clean_outline",
    "make_shape",
    "penetration",
    "rotation",
    "wrap",
]
