"""The search: cells placed one at a time into the free corner of the rectangle that fewest pieces fit.

A convex corner of the part of the rectangle not yet covered (a rectangle corner, a point on a side
where a cell ends, a fracture corner two cells already meet at) must be a corner of exactly one
more cell, whose corner angle is at most the free angle there and whose first edge runs along the
free corner's first side, edge to edge with it: that fixes the cell's turn and place. Every piece's
corners are tried at the free corner with the fewest candidates (angles and edge lengths in the
cell's frame first, then the placement: inside the rectangle, overlapping no placed cell, edge to
edge with its neighbours); depth first, the closest fits first. Each complete tiling is a solution.

A piece may touch a side of the rectangle at a corner only: its cell's border edge was shorter than
the gap, and shrinking it along its fractures left a corner short of the side. Its cell is then cut
by the side (a short border edge of the cell, none of the piece's). Such a cell fills a free corner
between a side and a neighbour's edge with no corner of the piece: it is placed edge to edge along
that neighbour's edge instead, its cell corner beyond the side cut away (a "cut" candidate).

Everything is in metres and radians, the slab frame centred on the rectangle, length along x.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from bt_arrange.geometry import FloatArray
from bt_arrange.puzzle.refine import fit, fit_step
from bt_arrange.puzzle.shapes import Shape, penetration, rotation
from bt_arrange.shapes.polygon import signed_area_m2

TWO_PI = 2 * math.pi
#: A cell crossing a side by less than this is left uncut; cut corners closer than this are one.
CUT_MARGIN_M = 1e-6
#: (shape, corner, border in, border out, closing, cut): a piece's corner tried at a free corner.
Candidate = tuple[int, int, bool, bool, bool, bool]
#: A first placement, before the joint fit, may be off by this many times the tolerance: its
#: neighbours may still slide (a pair of pieces sharing a corner of the slab, say).
PLACE_SLACK = 2.0
#: A cell edge may differ from the neighbour's it meets by this many times the tolerance: where four or
#: more pieces nearly meet at a point, a short fracture between two of them vanished when the gap shrank
#: them (1.5 missed 12 pieces at 2 mm, seed 23, by 1.05 mm).
LENGTH_SLACK = 2.0


@dataclass(frozen=True)
class Tolerances:
    """How far a fit may be off: edge lengths and contacts, overlaps, corner clusters, angles."""

    length_m: float
    overlap_m: float
    cluster_m: float
    angle_rad: float
    side_m: float
    residual_m: float


@dataclass
class Placed:
    """A piece placed: slab point = rotation(turn) @ piece point + shift; its border flags and cell (slab frame)."""

    shape: int
    turn: float
    shift: FloatArray
    border: tuple[bool, ...]  # per cell edge (the cell cut by the rectangle's sides)
    cell: FloatArray
    cell_lengths: FloatArray
    out_angles: FloatArray  # direction of each cell edge in the slab frame
    centre: FloatArray
    radius: float
    corner_angles: FloatArray  # the cell's interior angle at each of its corners
    cut: tuple[bool, ...]  # per cell edge: made by a side cutting the cell (no edge of the piece)


@dataclass
class Sector:
    """A free corner: apex, its first side's direction ``start`` and angle ``span``, and what bounds it."""

    apex: FloatArray
    start: float
    span: float
    kind_a: str  # "cell" or "side": what the first side runs along
    length_a: float  # the cell edge's length, or the room left along the side
    kind_b: str
    length_b: float
    #: Along a cell's edge: that edge's corner at the apex and its far corner (None along a side).
    near_a: FloatArray | None = None
    far_a: FloatArray | None = None
    near_b: FloatArray | None = None
    far_b: FloatArray | None = None

    def corner(self) -> FloatArray:
        """Where a corner filling the whole free angle goes: the apex, or where a side meets a cell's edge.

        A cell's corner within the cluster tolerance of a side is taken onto the side for the apex;
        the edge's own line meets the side beyond it when the cell filling the corner is cut by that side.
        """
        first = np.array([math.cos(self.start), math.sin(self.start)])
        second = np.array([math.cos(self.start + self.span), math.sin(self.start + self.span)])
        if self.kind_a == "side" and self.kind_b == "cell" and self.near_b is not None:
            side, edge, near = first, second, self.near_b
        elif self.kind_a == "cell" and self.kind_b == "side" and self.near_a is not None:
            side, edge, near = second, first, self.near_a
        else:
            return self.apex
        cross = float(side[0] * edge[1] - side[1] * edge[0])
        if abs(cross) < 1e-6:
            return self.apex
        t = float((near - self.apex)[0] * edge[1] - (near - self.apex)[1] * edge[0]) / cross
        return np.asarray(self.apex + t * side, dtype=float)


@dataclass
class Search:
    """The search's state: shapes, the rectangle, tolerances, the placed cells and the solutions found."""

    shapes: list[Shape]
    half_l: float
    half_w: float
    gap: float
    tol: Tolerances
    max_nodes: int
    max_solutions: int
    placed: list[Placed] = field(default_factory=list)
    solutions: list[list[Placed]] = field(default_factory=list)
    nodes: int = 0
    deepest: int = 0
    exhausted: bool = True

    # ---- the rectangle ------------------------------------------------------------------------
    def sides(self) -> list[tuple[FloatArray, float, float]]:
        """Each side as (outward normal, offset, normal's angle): bottom, right, top, left."""
        return [
            (np.array([0.0, -1.0]), self.half_w, -math.pi / 2),
            (np.array([1.0, 0.0]), self.half_l, 0.0),
            (np.array([0.0, 1.0]), self.half_w, math.pi / 2),
            (np.array([-1.0, 0.0]), self.half_l, math.pi),
        ]

    def border_flags(self, shape: Shape, turn: float, shift: FloatArray) -> tuple[bool, ...]:
        """Which of the piece's edges, placed, lie on a side of the rectangle."""
        points = shape.points @ rotation(turn).T + shift
        directions = shape.directions @ rotation(turn).T
        flags = []
        cos_tol = math.cos(2 * self.tol.angle_rad)
        for k in range(shape.count):
            a, b = points[k], points[(k + 1) % shape.count]
            on = False
            for normal, offset, _ in self.sides():
                along = np.array([-normal[1], normal[0]])
                if (
                    float(directions[k] @ along) > cos_tol
                    and max(abs(float(normal @ a) - offset), abs(float(normal @ b) - offset)) < self.tol.side_m
                ):
                    on = True
            flags.append(on)
        return tuple(flags)

    def make_placed(self, index: int, turn: float, shift: FloatArray) -> Placed:
        """The piece placed at ``turn`` and ``shift``, its border found and its cell built."""
        shape = self.shapes[index]
        flags = self.border_flags(shape, turn, shift)
        cell, border, cut = self._cut(shape.cell(flags) @ rotation(turn).T + shift, flags)
        edges = np.roll(cell, -1, axis=0) - cell
        lengths = np.hypot(edges[:, 0], edges[:, 1])
        angles = np.arctan2(edges[:, 1], edges[:, 0])
        turns = (angles - np.roll(angles, 1) + math.pi) % TWO_PI - math.pi
        centre = cell.mean(axis=0)
        radius = float(np.max(np.hypot(*(cell - centre).T)))
        return Placed(index, turn, shift, border, cell, lengths, angles, centre, radius, math.pi - turns, cut)

    def _cut(self, cell: FloatArray, border: tuple[bool, ...]) -> tuple[FloatArray, tuple[bool, ...], tuple[bool, ...]]:
        """The cell cut by every side it crosses and has no border edge on, its border and cut flags per edge.

        A side the piece has a border edge on is left alone: that edge is the cell's, fitted later.
        """
        cut = tuple(False for _ in border)
        cos_tol = math.cos(2 * self.tol.angle_rad)
        for normal, offset, _ in self.sides():
            heights = cell @ normal - offset
            if float(np.max(heights)) <= CUT_MARGIN_M:
                continue
            along = np.array([-normal[1], normal[0]])
            directions = np.roll(cell, -1, axis=0) - cell
            if any(
                flag and float(d @ along) > cos_tol * float(np.hypot(*d))
                for flag, d in zip(border, directions, strict=True)
            ):
                continue
            points, flags, cuts = [], [], []
            count = len(cell)
            for k in range(count):
                here, after = float(heights[k]), float(heights[(k + 1) % count])
                if here <= 0:
                    points.append(cell[k])
                    flags.append(border[k])
                    cuts.append(cut[k])
                if (here <= 0) != (after <= 0):
                    meet = cell[k] + (cell[(k + 1) % count] - cell[k]) * (here / (here - after))
                    points.append(meet)
                    flags.append(here <= 0 or border[k])  # leaving: the side's edge follows
                    cuts.append(here <= 0 or cut[k])
            kept = [k for k in range(len(points)) if float(np.hypot(*(points[k] - points[k - 1]))) > CUT_MARGIN_M]
            cell = np.array([points[k] for k in kept])
            border = tuple(flags[k] for k in kept)
            cut = tuple(cuts[k] for k in kept)
        return cell, border, cut

    # ---- free corners -------------------------------------------------------------------------
    def sectors(self) -> list[Sector]:
        """Every convex free corner of the part of the rectangle not yet covered."""
        points: list[FloatArray] = []
        members: list[list[tuple[int, int]]] = []
        for i, placed in enumerate(self.placed):
            for k, point in enumerate(placed.cell):
                for c, centre in enumerate(points):
                    if float(np.hypot(*(point - centre))) < self.tol.cluster_m:
                        members[c].append((i, k))
                        break
                else:
                    points.append(point.copy())
                    members.append([(i, k)])
        for corner in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
            point = np.array([corner[0] * self.half_l, corner[1] * self.half_w])
            if all(float(np.hypot(*(point - p))) >= self.tol.cluster_m for p in points):
                points.append(point)
                members.append([])
        found = []
        for point, group in zip(points, members, strict=True):
            if group:
                point = np.mean([self.placed[i].cell[k] for i, k in group], axis=0)
            found.extend(self._free_at(point, group, points))
        return found

    def _free_at(self, point: FloatArray, group: list[tuple[int, int]], points: list[FloatArray]) -> list[Sector]:
        intervals: list[tuple[float, float, str, float]] = []  # start, end, kind, length of its start/end edge
        apex = point.copy()
        on_sides = []
        for s, (normal, offset, angle) in enumerate(self.sides()):
            if abs(float(normal @ point) - offset) < self.tol.cluster_m:
                on_sides.append(s)
                apex = apex - normal * (float(normal @ apex) - offset)
                intervals.append((angle - math.pi / 2, angle + math.pi / 2, "side", float(s)))
        cell_edges: dict[tuple[float, str], float] = {}
        for member, (i, k) in enumerate(group):
            placed = self.placed[i]
            start = float(placed.out_angles[k])
            alpha = float(placed.corner_angles[k])
            intervals.append((start, start + alpha, "cell", float(member)))  # which member of the group
            # the interval's start runs along edge k (out), its end along edge k-1 (in)
            cell_edges[(start % TWO_PI, "out")] = float(placed.cell_lengths[k])
            cell_edges[((start + alpha) % TWO_PI, "in")] = float(placed.cell_lengths[k - 1])
        if not intervals:
            return []
        normalised = sorted(((s % TWO_PI, s % TWO_PI + (e - s), kind, ref) for s, e, kind, ref in intervals))
        first = normalised[0]
        end, end_kind, end_ref = first[1], first[2], first[3]
        gaps: list[tuple[float, float, str, float, str, float]] = []
        for start, stop, kind, ref in [*normalised[1:], (first[0] + TWO_PI, first[1] + TWO_PI, first[2], first[3])]:
            if start > end + self.tol.angle_rad:
                gaps.append((end, start, end_kind, end_ref, kind, ref))
            if stop > end:
                end, end_kind, end_ref = stop, kind, ref
        sectors = []
        for a, b, kind_a, ref_a, kind_b, ref_b in gaps:
            span = b - a
            if span >= math.pi - self.tol.angle_rad:
                continue
            length_a = self._edge_length(a, kind_a, ref_a, "in", cell_edges, apex, points)
            length_b = self._edge_length(b, kind_b, ref_b, "out", cell_edges, apex, points)
            sector = Sector(apex, a, span, kind_a, length_a, kind_b, length_b)
            if kind_a == "cell":  # the end of a cell's corner: along its edge k-1, reversed
                i, k = group[int(ref_a)]
                sector.near_a, sector.far_a = self.placed[i].cell[k], self.placed[i].cell[k - 1]
            if kind_b == "cell":  # the start of a cell's corner: along its edge k
                i, k = group[int(ref_b)]
                cell = self.placed[i].cell
                sector.near_b, sector.far_b = cell[k], cell[(k + 1) % len(cell)]
            sectors.append(sector)
        return sectors

    def _edge_length(
        self,
        angle: float,
        kind: str,
        ref: float,
        end: str,
        cell_edges: dict[tuple[float, str], float],
        apex: FloatArray,
        points: list[FloatArray],
    ) -> float:
        if kind == "cell":
            best, length = math.inf, 0.0
            for (edge_angle, which), value in cell_edges.items():
                if which != end:
                    continue
                off = abs((edge_angle - angle + math.pi) % TWO_PI - math.pi)
                if off < best:
                    best, length = off, value
            return length
        direction = np.array([math.cos(angle), math.sin(angle)])
        normal, offset, _ = self.sides()[int(ref)]
        room = math.inf
        for other in points:
            if abs(float(normal @ other) - offset) < self.tol.cluster_m:
                ahead = float((other - apex) @ direction)
                if ahead > self.tol.cluster_m:
                    room = min(room, ahead)
        for corner in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
            point = np.array([corner[0] * self.half_l, corner[1] * self.half_w])
            ahead = float((point - apex) @ direction)
            if ahead > self.tol.cluster_m and abs(float(normal @ point) - offset) < 1e-9:
                room = min(room, ahead)
        return room

    # ---- candidates ---------------------------------------------------------------------------
    def prefilter(self, sector: Sector, free: list[int]) -> list[Candidate]:
        """(shape, corner, border in, border out, closing, cut) of every piece corner that can fill the free corner.

        Cut candidates (the last flag) come after the others: a corner of the piece beyond the side.
        """
        tol = self.tol
        least_angle = {i: float(np.min(self.shapes[i].angles)) for i in free}
        found = []
        for i in free:
            shape = self.shapes[i]
            others = [least_angle[j] for j in free if j != i]
            least_other = min(others) if others else math.inf
            for k in range(shape.count):
                alpha = float(shape.angles[k])
                if alpha > sector.span + tol.angle_rad:
                    continue
                closing = alpha > sector.span - tol.angle_rad
                if not closing and sector.span - alpha < least_other - tol.angle_rad:
                    continue
                border_out = sector.kind_a == "side"
                border_in = closing and sector.kind_b == "side"
                out_lengths = shape.cell_lengths[
                    k, [4 * border_in + 2 * border_out, 4 * border_in + 2 * border_out + 1]
                ]
                if not _length_fits(
                    out_lengths, sector.kind_a, sector.length_a, tol.length_m, self._on_side(sector.far_a)
                ):
                    continue
                if closing:
                    in_lengths = shape.cell_lengths[k - 1, [2 * border_in + border_out, 4 + 2 * border_in + border_out]]
                    if not _length_fits(
                        in_lengths, sector.kind_b, sector.length_b, tol.length_m, self._on_side(sector.far_b)
                    ):
                        continue
                found.append((i, k, border_in, border_out, closing, False))
        return found + self._cut_candidates(sector, free)

    def _on_side(self, point: FloatArray | None) -> bool:
        """Whether a neighbour's far corner lies on a side: the cell edge along it may be cut there."""
        return point is not None and any(abs(float(n @ point) - o) < self.tol.cluster_m for n, o, _ in self.sides())

    def _cut_candidates(self, sector: Sector, free: list[int]) -> list[Candidate]:
        """The piece corners that may lie beyond the side bounding the free corner, their cell cut by it.

        The free corner lies between a side and a neighbour's edge; the piece's edge along that
        neighbour's, longer than it in the cell, runs past the side, at an angle less than the free one.
        """
        if {sector.kind_a, sector.kind_b} != {"cell", "side"}:
            return []
        along_first = sector.kind_a == "cell"
        room = sector.length_a if along_first else sector.length_b
        found: list[Candidate] = []
        for i in free:
            shape = self.shapes[i]
            for k in range(shape.count):
                if float(shape.angles[k]) >= sector.span - self.tol.angle_rad:
                    continue
                edge = k if along_first else k - 1
                if float(shape.cell_lengths[edge, 0]) < room - self.tol.length_m:
                    continue
                found.append((i, k, False, False, False, True))
        return found

    def place(self, sector: Sector, candidate: Candidate) -> tuple[float, Placed] | None:
        """The candidate placed in the free corner, fitted to its neighbours, its misfit; None: no fit."""
        i, k, border_in, border_out, closing, cut = candidate
        shape = self.shapes[i]
        if cut:
            turn, shift = self._cut_pose(sector, shape, k)
        else:
            corner = shape.cell_corner(k, border_in, border_out)
            turn = sector.start - math.atan2(shape.directions[k, 1], shape.directions[k, 0])
            if closing:
                d_in = shape.directions[k - 1]
                other = sector.start + sector.span + math.pi - math.atan2(d_in[1], d_in[0])
                delta = (other - turn + math.pi) % TWO_PI - math.pi
                turn += delta / 2
            anchor = sector.corner() if closing else sector.apex
            if float(np.hypot(*(anchor - sector.apex))) > 2 * self.tol.cluster_m:
                anchor = sector.apex
            shift = anchor - rotation(turn) @ corner
        placed = self.make_placed(i, turn, shift)
        if cut and not self._cut_at(placed, sector.apex):
            return None  # no side cuts the cell at the free corner: the piece's corner falls short of it
        for _ in range(2):
            rows = self._contacts(placed)
            if rows is None:
                return None
            step = fit_step(rows, placed.centre)
            if step is None:
                break
            d_turn, d_shift = step
            shift = rotation(d_turn) @ (placed.shift - placed.centre) + placed.centre + d_shift
            placed = self.make_placed(i, placed.turn + d_turn, shift)
        rows = self._contacts(placed)
        if rows is None or not self._fits(placed, self.placed, PLACE_SLACK):
            return None
        misfit = float(np.sqrt(np.mean([r[2] ** 2 for r in rows]))) if rows else 0.0
        return misfit, placed

    def _cut_pose(self, sector: Sector, shape: Shape, k: int) -> tuple[float, FloatArray]:
        """A cut candidate's turn and shift: its edge along the neighbour's, their far ends together."""
        if sector.kind_a == "cell":  # edge k runs out along the first side, to the neighbour's far corner
            direction = shape.directions[k]
            turn = sector.start - math.atan2(direction[1], direction[0])
            far = shape.cell_corner((k + 1) % shape.count, False, False)
            end = sector.far_a
        else:  # edge k-1 runs in along the second side, from the neighbour's far corner
            direction = shape.directions[k - 1]
            turn = sector.start + sector.span + math.pi - math.atan2(direction[1], direction[0])
            far = shape.cell_corner((k - 1) % shape.count, False, False)
            end = sector.far_b
        assert end is not None  # a cut candidate's free corner lies along a cell's edge
        return turn, end - rotation(turn) @ far

    def _cut_at(self, placed: Placed, apex: FloatArray) -> bool:
        """Whether a side cuts the placed cell at ``apex``: a corner of a cut edge there."""
        count = len(placed.cell)
        return any(
            (placed.cut[k] or placed.cut[k - 1]) and float(np.hypot(*(placed.cell[k] - apex))) < self.tol.cluster_m
            for k in range(count)
        )

    def _fits(self, placed: Placed, others: list[Placed], slack: float) -> bool:
        """Whether the piece and its cell stay in the rectangle and out of the others, within ``slack`` x tolerance."""
        limit = slack * self.tol.overlap_m
        points = self.shapes[placed.shape].points @ rotation(placed.turn).T + placed.shift
        for normal, offset, _ in self.sides():
            if max(float(np.max(placed.cell @ normal)), float(np.max(points @ normal))) - offset > limit:
                return False
        for other in others:
            if float(np.hypot(*(placed.centre - other.centre))) > placed.radius + other.radius:
                continue
            if penetration(placed.cell, other.cell) > limit:
                return False
        return True

    def _contacts(self, placed: Placed) -> list[tuple[FloatArray, FloatArray, float]] | None:
        """Rows (point on the cell, normal, misfit) of its contacts; None: an edge meets another off its ends.

        A contact is a cell edge along a placed cell's edge (antiparallel, within the length
        tolerance): both ends must meet that edge's ends (edge to edge), each giving a row across
        and one along. A border edge gives a row across its side at each end.
        """
        tol = self.tol
        rows: list[tuple[FloatArray, FloatArray, float]] = []
        count = len(placed.cell)
        cos_tol = math.cos(2 * tol.angle_rad)
        for k in range(count):
            a, b = placed.cell[k], placed.cell[(k + 1) % count]
            direction = (b - a) / max(float(np.hypot(*(b - a))), 1e-12)
            if placed.cut[k]:
                continue  # on its side by construction: it says nothing of the pose
            if placed.border[k]:
                for normal, offset, _ in self.sides():
                    if float(direction @ np.array([-normal[1], normal[0]])) > cos_tol:
                        for p in (a, b):
                            rows.append((p, normal, float(normal @ p) - offset))
                continue
            normal_k = np.array([direction[1], -direction[0]])
            for other in self.placed:
                if float(np.hypot(*(placed.centre - other.centre))) > placed.radius + other.radius + tol.length_m:
                    continue
                m = len(other.cell)
                for j in range(m):
                    if other.border[j]:
                        continue
                    c, d = other.cell[j], other.cell[(j + 1) % m]
                    other_dir = (d - c) / max(float(np.hypot(*(d - c))), 1e-12)
                    if float(direction @ other_dir) > -cos_tol:
                        continue
                    if abs(float(normal_k @ (c - a))) > tol.length_m or abs(float(normal_k @ (d - a))) > tol.length_m:
                        continue
                    lo = min(float((c - a) @ direction), float((d - a) @ direction))
                    hi = max(float((c - a) @ direction), float((d - a) @ direction))
                    if min(hi, float((b - a) @ direction)) - max(lo, 0.0) <= tol.length_m:
                        continue
                    ends = (PLACE_SLACK + 1) * tol.length_m
                    if float(np.hypot(*(a - d))) > ends or float(np.hypot(*(b - c))) > ends:
                        return None
                    other_normal = np.array([other_dir[1], -other_dir[0]])
                    for p, q in ((a, d), (b, c)):
                        rows.append((p, -other_normal, float(-other_normal @ (p - q))))
                        rows.append((p, other_dir, float(other_dir @ (p - q))))
        return rows

    # ---- depth first --------------------------------------------------------------------------
    def run(self) -> None:
        """Search from the empty rectangle until every tiling is found or a cap is reached."""
        self._grow(list(range(len(self.shapes))))

    def _grow(self, free: list[int]) -> None:
        if len(self.solutions) >= self.max_solutions:
            self.exhausted = False
            return
        if self.nodes >= self.max_nodes:
            self.exhausted = False
            return
        self.nodes += 1
        self.deepest = max(self.deepest, len(self.placed))
        if not free:
            covered = sum(signed_area_m2(p.cell) for p in self.placed)
            slack = self.tol.length_m * 2 * (self.half_l + self.half_w)
            if abs(covered - 4 * self.half_l * self.half_w) <= slack:
                self.solutions.append(list(self.placed))
            return
        best: tuple[Sector, list[Candidate]] | None = None
        for sector in self.sectors():
            candidates = self.prefilter(sector, free)
            if best is None or len(candidates) < len(best[1]):
                best = (sector, candidates)
            if not candidates:
                return
        if best is None:
            return
        sector, candidates = best
        fits = []
        for candidate in candidates:
            result = self.place(sector, candidate)
            if result is not None:
                fits.append(result)
        fits.sort(key=lambda item: item[0])
        before = self.placed
        for _, placed in fits:
            refitted = self.refit([*before, placed])
            if refitted is None:
                continue
            self.placed = refitted
            self._grow([i for i in free if i != placed.shape])
            self.placed = before

    def refit(self, placed: list[Placed]) -> list[Placed] | None:
        """The placed pieces fitted jointly on their measured outlines; None when their contacts misfit.

        Each place made from the ones before carries their errors; fitting them all again at each
        step keeps the free corners where the next piece's cell really is.
        """
        shapes = [self.shapes[p.shape] for p in placed]
        fitted = fit(
            shapes,
            np.array([p.turn for p in placed]),
            np.array([p.shift for p in placed]),
            self.half_l,
            self.half_w,
            self.gap,
        )
        if not fitted.residual_m <= self.tol.residual_m:
            return None
        refitted = [
            self.make_placed(p.shape, float(turn), shift)
            for p, turn, shift in zip(placed, fitted.turns, fitted.shifts, strict=True)
        ]
        if not self._apart(refitted[-1], refitted[:-1]):
            return None
        return refitted

    def _apart(self, placed: Placed, others: list[Placed]) -> bool:
        """Whether the piece (not its cell) lies in the rectangle and overlaps no other piece, within tolerance."""
        points = self.shapes[placed.shape].points @ rotation(placed.turn).T + placed.shift
        for normal, offset, _ in self.sides():
            if float(np.max(points @ normal)) - offset > self.tol.overlap_m:
                return False
        for other in others:
            if float(np.hypot(*(placed.centre - other.centre))) > placed.radius + other.radius:
                continue
            other_points = self.shapes[other.shape].points @ rotation(other.turn).T + other.shift
            if penetration(points, other_points) > self.tol.overlap_m - self.gap:
                return False
        return True


def _length_fits(lengths: FloatArray, kind: str, target: float, tolerance: float, cut: bool = False) -> bool:
    """Whether a cell edge fits along the free corner's side: a cell's edge (longer where a side cuts it) or a side."""
    if kind == "cell" and cut:
        return bool(np.max(lengths) >= target - LENGTH_SLACK * tolerance)
    if kind == "cell":
        return bool(np.min(np.abs(lengths - target)) <= LENGTH_SLACK * tolerance)
    return bool(np.min(lengths) <= target + PLACE_SLACK * tolerance)


__all__ = ["Placed", "Search", "Sector", "Tolerances"]
