"""The search: cells placed one at a time into the free corner of the rectangle that fewest pieces fit.

A convex corner of the part of the rectangle not yet covered (a rectangle corner, a point on a side
where a cell ends, a fracture corner two cells already meet at) must be a corner of exactly one
more cell, whose corner angle is at most the free angle there and whose first edge runs along the
free corner's first side, edge to edge with it: that fixes the cell's turn and place. Every piece's
corners are tried at the free corner with the fewest candidates (angles and edge lengths in the
cell's frame first, then the placement: inside the rectangle, overlapping no placed cell, edge to
edge with its neighbours); depth first, the closest fits first. Each complete tiling is a solution.

Everything is in metres and radians, the slab frame centred on the rectangle, length along x.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from bt_arrange.geometry import FloatArray
from bt_arrange.puzzle.refine import fit
from bt_arrange.puzzle.shapes import Shape, penetration, rotation, signed_area

TWO_PI = 2 * math.pi
#: A first placement, before the joint fit, may be off by this many times the tolerance: its
#: neighbours may still slide (a pair of pieces sharing a corner of the slab, say).
PLACE_SLACK = 2.0


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
    border: tuple[bool, ...]
    cell: FloatArray
    cell_lengths: FloatArray
    out_angles: FloatArray  # direction of each cell edge in the slab frame
    centre: FloatArray
    radius: float


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
        cell = shape.cell(flags) @ rotation(turn).T + shift
        edges = np.roll(cell, -1, axis=0) - cell
        lengths = np.hypot(edges[:, 0], edges[:, 1])
        angles = np.arctan2(edges[:, 1], edges[:, 0])
        centre = cell.mean(axis=0)
        radius = float(np.max(np.hypot(*(cell - centre).T)))
        return Placed(index, turn, shift, flags, cell, lengths, angles, centre, radius)

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
        for i, k in group:
            placed = self.placed[i]
            start = float(placed.out_angles[k])
            alpha = float(self.shapes[placed.shape].angles[k])
            intervals.append((start, start + alpha, "cell", 0.0))
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
            sectors.append(Sector(apex, a, span, kind_a, length_a, kind_b, length_b))
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
    def prefilter(self, sector: Sector, free: list[int]) -> list[tuple[int, int, bool, bool, bool]]:
        """(shape, corner, border in, border out, closing) of every piece corner that can fill the free corner."""
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
                if not _length_fits(out_lengths, sector.kind_a, sector.length_a, tol.length_m):
                    continue
                if closing:
                    in_lengths = shape.cell_lengths[k - 1, [2 * border_in + border_out, 4 + 2 * border_in + border_out]]
                    if not _length_fits(in_lengths, sector.kind_b, sector.length_b, tol.length_m):
                        continue
                found.append((i, k, border_in, border_out, closing))
        return found

    def place(self, sector: Sector, candidate: tuple[int, int, bool, bool, bool]) -> tuple[float, Placed] | None:
        """The candidate placed in the free corner, fitted to its neighbours, its misfit; None: no fit."""
        i, k, border_in, border_out, closing = candidate
        shape = self.shapes[i]
        corner = shape.cell_corner(k, border_in, border_out)
        turn = sector.start - math.atan2(shape.directions[k, 1], shape.directions[k, 0])
        if closing:
            d_in = shape.directions[k - 1]
            other = sector.start + sector.span + math.pi - math.atan2(d_in[1], d_in[0])
            delta = (other - turn + math.pi) % TWO_PI - math.pi
            turn += delta / 2
        shift = sector.apex - rotation(turn) @ corner
        placed = self.make_placed(i, turn, shift)
        for _ in range(2):
            rows = self._contacts(placed)
            if rows is None:
                return None
            step = _fit_step(rows, placed.centre)
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

    def _fits(self, placed: Placed, others: list[Placed], slack: float) -> bool:
        """Whether the cell stays in the rectangle and out of the others, within ``slack`` times the tolerance."""
        limit = slack * self.tol.overlap_m
        for normal, offset, _ in self.sides():
            if float(np.max(placed.cell @ normal)) - offset > limit:
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
            covered = sum(signed_area(p.cell) for p in self.placed)
            slack = self.tol.length_m * 2 * (self.half_l + self.half_w)
            if abs(covered - 4 * self.half_l * self.half_w) <= slack:
                self.solutions.append(list(self.placed))
            return
        best: tuple[Sector, list[tuple[int, int, bool, bool, bool]]] | None = None
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


def _length_fits(lengths: FloatArray, kind: str, target: float, tolerance: float) -> bool:
    if kind == "cell":
        return bool(np.min(np.abs(lengths - target)) <= tolerance)
    return bool(np.min(lengths) <= target + PLACE_SLACK * tolerance)


def _fit_step(rows: list[tuple[FloatArray, FloatArray, float]], centre: FloatArray) -> tuple[float, FloatArray] | None:
    """The small turn (about ``centre``) and shift that best cancel the rows' misfits, or None if under-determined."""
    if len(rows) < 3:
        return None
    a = np.zeros((len(rows), 3))
    b = np.zeros(len(rows))
    for r, (point, normal, misfit) in enumerate(rows):
        arm = point - centre
        a[r] = (float(normal @ np.array([-arm[1], arm[0]])), normal[0], normal[1])
        b[r] = -misfit
    solution, _, rank, _ = np.linalg.lstsq(a, b, rcond=None)
    if rank < 3:
        return None
    return float(solution[0]), solution[1:]


__all__ = ["Placed", "Search", "Sector", "Tolerances"]
