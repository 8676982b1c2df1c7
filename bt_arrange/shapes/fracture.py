"""Frescoes: a rectangular slab broken into irregular pieces, each a :class:`Prism` at its place in the whole.

The fracture is a Voronoi partition of the slab from sites drawn from the seed (irregular cuts,
no grid), clipped to the slab's rectangle. Every piece is then shrunk by half the gap along each
fracture, not along the slab's outer edge, so that the pieces reassembled leave exactly
``gap_m`` between neighbours (any two points of different pieces are at least the gap apart: a
segment between them leaves one cell and enters the other, each at least half the gap from its
point). A Voronoi cell is convex, and so is a convex cell clipped by half-planes: every piece is
a convex prism, which keeps the layout's separating-axis tests exact.

A draw whose pieces are not all parts the 2F-85 can handle (``Prism.problems``: a side under the
camera's 10 mm between two corners, no grasp, too wide) is redrawn from the next sub-seed
(``numpy.random.default_rng([seed, draw])``), so a seed always gives the same fracture.

Each piece's frame is its area centroid, its x axis along the closing axis of its preferred grasp
(the pads close along x): the layout places and releases parts across their frame's x or y axis.
Its target is the centroid's place in the whole and the turn of that frame, with the whole's pose
applied. Everything is in metres and radians.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from bt_arrange.errors import PlanError
from bt_arrange.geometry import FloatArray
from bt_arrange.shapes.antipodal import BESIDE_PADS_M, MAX_RISE_M
from bt_arrange.shapes.gripper import ROBOTIQ_2F85, Gripper
from bt_arrange.shapes.polygon import boundary_samples, distance_to_outline_m
from bt_arrange.shapes.prism import Prism, outline_problem

#: A fresco is broken into this many pieces at least and at most.
MIN_PIECES, MAX_PIECES = 3, 12
#: The least gap along a fracture at all: the layout's least gap between two targets at its finest
#: threshold (``ManipulationSettings.finest_gap_m``). A plan's threshold asks for more
#: (``ManipulationSettings.gap_for_threshold_m``: twice it, 2 mm at 1 mm or more).
MIN_GAP_M = 0.0005
#: Draws tried before a fresco is refused (each from the next sub-seed).
MAX_DRAWS = 400
#: Sites closer than this share of the mean spacing are redrawn at once: slivers are never graspable.
SITE_SPACING_SHARE = 0.55
#: A piece must misfit itself turned to any other yaw by this much (``yaw_cue_m``): 4 pixels of the
#: top camera, where its registration tells two yaws apart within 1 pixel.
MIN_YAW_CUE_M = 0.002
#: Lloyd steps moving each site to its cell's centroid: rounder pieces, still irregular.
LLOYD_STEPS = 2


@dataclass(frozen=True)
class Piece:
    """One piece: its ``prism`` (own frame), and its target on the table ``(x_m, y_m, yaw_rad)``.

    ``slab_outline_m`` is the piece's top face in the slab's frame (the slab centred on the origin,
    its length along x), as cut: what the tests measure gaps and areas on.
    """

    index: int
    prism: Prism
    x_m: float
    y_m: float
    yaw_rad: float
    slab_outline_m: FloatArray


_VECDOT = getattr(np, "vecdot", None)


def _dots(rows: FloatArray, vector: FloatArray) -> list[float]:
    """Each row's dot product with ``vector`` (or with its own row of ``vector``), as ``float(vector @ row)`` gives it.

    Not ``rows @ vector``: a matrix product sums its products in another order and rounds
    otherwise, where ``numpy.vecdot`` (numpy 2) takes each row's dot as ``@`` takes a pair's.
    The fracture's corners are so the same, to the bit, as one pair at a time gave them.
    """
    if _VECDOT is not None:
        return list(_VECDOT(rows, vector).tolist())
    if vector.ndim == 1:
        return [float(vector @ row) for row in rows]
    return [float(row @ other) for row, other in zip(rows, vector, strict=True)]


def _clipped(corners: list[tuple[float, float]], sides: list[float]) -> list[tuple[float, float]]:
    """The corners on a line's inner side (``sides`` each corner's signed distance, positive outside) and the crossings.

    A crossing ``a + (b - a) t`` is worked per coordinate in floats, each step rounded as numpy's
    element-wise steps round it. A polygon wholly inside comes back as it was, one wholly outside
    empty: as a rough test by a margin once decided, to the same corners.
    """
    if max(sides) <= 0:
        return corners
    out: list[tuple[float, float]] = []
    count = len(corners)
    for k in range(count):
        (ax, ay), (bx, by) = corners[k], corners[(k + 1) % count]
        da, db = sides[k], sides[(k + 1) % count]
        if da <= 0:
            out.append((ax, ay))
        if da * db < 0:
            t = da / (da - db)
            out.append((ax + (bx - ax) * t, ay + (by - ay) * t))
    return out


def _bisectors(sites: FloatArray, shrink_m: float) -> tuple[list[list[tuple[float, float]]], list[list[float]]]:
    """Every pair's unit normal from site i towards site j, and its bisector's offset less ``shrink_m``, at once.

    To the bit what ``other - site`` divided by its ``numpy.linalg.norm`` (the square root of its
    own dot product) and ``float(normal @ (site + other)) / 2 - shrink_m`` give pair by pair.
    """
    count = len(sites)
    towards = (sites[None, :, :] - sites[:, None, :]).reshape(-1, 2)
    squared = np.array(_dots(towards, towards))
    squared[:: count + 1] = 1.0  # a site and itself: no bisector, never used
    normals = towards / np.sqrt(squared)[:, None]
    sums = (sites[:, None, :] + sites[None, :, :]).reshape(-1, 2)
    offsets = np.array(_dots(normals, sums)) / 2 - shrink_m
    return normals.reshape(count, count, 2).tolist(), offsets.reshape(count, count).tolist()


def _cells(sites: FloatArray, half_l: float, half_w: float, shrink_m: float) -> list[FloatArray]:
    """Each site's Voronoi cell within the slab, moved ``shrink_m`` in from every bisector.

    Each cell is clipped by the bisectors in the sites' order, every cell's corners against the
    same site's bisectors taken in one product (``_dots``): the corners are those of clipping
    one cell by one bisector at a time, to the bit.
    """
    count = len(sites)
    slab = [(-half_l, -half_w), (half_l, -half_w), (half_l, half_w), (-half_l, half_w)]
    normals, offsets = _bisectors(sites, shrink_m)
    polygons = [slab] * count
    for j in range(count):
        owners = [i for i in range(count) if i != j and polygons[i]]
        rows = [corner for i in owners for corner in polygons[i]]
        towards = [normals[i][j] for i in owners for _ in polygons[i]]
        products = _dots(np.array(rows), np.array(towards))
        start = 0
        for i in owners:
            size, offset = len(polygons[i]), offsets[i][j]
            polygons[i] = _clipped(polygons[i], [side - offset for side in products[start : start + size]])
            start += size
    return [_dedupe(np.array(polygon) if polygon else np.zeros((0, 2))) for polygon in polygons]


def _dedupe(points: FloatArray, tolerance_m: float = 1e-7) -> FloatArray:
    """The polygon without repeated corners or corners on a straight line (clipping leaves both)."""
    if len(points) == 0:
        return np.zeros((0, 2))
    steps = points - np.concatenate((points[-1:], points[:-1]))
    apart = np.hypot(steps[:, 0], steps[:, 1]) > tolerance_m
    corners = [corner for corner, keep in zip(points.tolist(), apart.tolist(), strict=True) if keep]
    changed = True
    while changed and len(corners) > 3:
        changed = False
        for k in range(len(corners)):
            (bx, by), (hx, hy), (ax, ay) = corners[k - 1], corners[k], corners[(k + 1) % len(corners)]
            if abs((hx - bx) * (ay - hy) - (hy - by) * (ax - hx)) < 1e-12:
                del corners[k]
                changed = True
                break
    return np.array(corners) if corners else np.zeros((0, 2))


def _sites(rng: np.random.Generator, pieces: int, half_l: float, half_w: float) -> FloatArray:
    """``pieces`` sites in the slab, none nearer another than a share of the mean spacing."""
    spacing = SITE_SPACING_SHARE * math.sqrt(4 * half_l * half_w / pieces)
    sites: list[FloatArray] = []
    while len(sites) < pieces:
        candidate = np.array([rng.uniform(-half_l, half_l), rng.uniform(-half_w, half_w)])
        if all(float(np.hypot(*(candidate - s))) >= spacing for s in sites):
            sites.append(candidate)
    array = np.array(sites)
    for _ in range(LLOYD_STEPS):
        array = np.array([_area_centroid(cell) for cell in _cells(array, half_l, half_w, 0.0)])
    return array


def _area_centroid(points: FloatArray) -> FloatArray:
    x, y = points[:, 0], points[:, 1]
    # Each corner's next (numpy.roll by one, without its general axis handling: a tenth of a draw's time).
    x_next, y_next = np.concatenate((x[1:], x[:1])), np.concatenate((y[1:], y[:1]))
    cross = x * y_next - x_next * y
    area = 0.5 * float(np.sum(cross))
    return np.array([float(np.sum((x + x_next) * cross)), float(np.sum((y + y_next) * cross))]) / (6.0 * area)


def _cue_turns() -> FloatArray:
    """The turns of ``yaw_cue_m`` (20 to 340 degrees, 2 degree steps), each as the matrix a row vector is turned by."""
    matrices = []
    for degrees in range(20, 341, 2):
        turn = math.radians(degrees)
        c, s = math.cos(turn), math.sin(turn)
        matrices.append([[c, s], [-s, c]])
    return np.array(matrices)


#: ``yaw_cue_m``'s turns, stacked: every turn of a piece is measured at once.
CUE_TURNS = _cue_turns()


#: The half turn among ``CUE_TURNS`` (180 degrees): a piece cut from a long slab, nearly a rectangle,
#: comes back to itself under it, and most draws of a long slab fall on it.
HALF_TURN = CUE_TURNS[[(180 - 20) // 2]]
#: How far under ``MIN_YAW_CUE_M`` the half turn alone must score to refuse a piece before its grasp
#: search (metres): the half turn measured alone and among every turn differ in rounding only.
CUE_SCREEN_MARGIN_M = 1e-9


def _misfit_m(prism: Prism, turns: FloatArray) -> FloatArray:
    """The 80th percentile of the outline's distance to itself turned by each of ``turns``."""
    points = prism.outline_m
    turned = np.matmul(boundary_samples(points)[None], turns)
    return np.percentile(distance_to_outline_m(turned, points), 80, axis=1)


def yaw_cue_m(prism: Prism) -> float:
    """How clearly the outline shows its yaw: its least misfit, turned about its centroid to any other yaw.

    The 80th percentile of the outline's distance to itself turned by 20 to 340 degrees (2 degree
    steps), the least over the turns. A piece nearly symmetric under some turn (a near-rectangle
    under a half turn) scores low: the camera's registration could not tell those two yaws apart.
    Every turn at once (161 x 160 sample points): the figure of measuring one turn after the other,
    to the last bit, in a fifth of the time.
    """
    return float(np.min(_misfit_m(prism, CUE_TURNS)))


#: How far beyond ``_too_wide_to_grasp``'s bound a convex piece must be (metres) for its verdict: far
#: above the rounding of its products.
TOO_WIDE_MARGIN_M = 1e-3


def _too_wide_to_grasp(points: FloatArray, gripper: Gripper) -> bool:
    """True when no grasp search could find a grasp on this convex outline: it is too wide every way.

    Where the pads could hold a convex outline (``bt_arrange.shapes.antipodal``), across at most
    ``max_grasp_width_m``, the outline rises no more than ``MAX_RISE_M`` within ``BESIDE_PADS_M``
    beyond them; its edges being straight and turning one way, it rises no faster further on, so it
    is at most ``max_grasp_width_m + 2 MAX_RISE_M + 2 (MAX_RISE_M / BESIDE_PADS_M) x length`` wide
    across those pads. A piece whose least width (along one of its edges' normals) is wider, with its
    diameter as the length, has no grasp: a slab broken into pieces too large is refused each draw
    without a search along every closing axis at every half millimetre.
    """
    edges = np.roll(points, -1, axis=0) - points
    normals = np.column_stack([edges[:, 1], -edges[:, 0]]) / np.hypot(edges[:, 0], edges[:, 1])[:, None]
    spans = points @ normals.T
    least_width = float(np.min(spans.max(axis=0) - spans.min(axis=0)))
    diameter = float(np.max(np.hypot(*(points[:, None, :] - points[None, :, :]).transpose(2, 0, 1))))
    bound = gripper.max_grasp_width_m + 2 * MAX_RISE_M + 2 * (MAX_RISE_M / BESIDE_PADS_M) * diameter
    return least_width > bound + TOO_WIDE_MARGIN_M


def _least_width_m(prism: Prism) -> float:
    """The outline's least width across one of its edges (its width along that edge's normal)."""
    points = prism.outline_m
    edges = np.concatenate((points[1:], points[:1])) - points
    normals = np.column_stack([edges[:, 1], -edges[:, 0]]) / np.hypot(edges[:, 0], edges[:, 1])[:, None]
    spans = points @ normals.T
    return float(np.min(spans.max(axis=0) - spans.min(axis=0)))


def _judged(
    cells: list[FloatArray], height_m: float, gripper: Gripper, settle_turns: int = 0
) -> list[tuple[Prism, float]] | None:
    """Every cell as a prism whose frame's x axis is its preferred grasp's closing axis, and that frame's turn.

    None when a piece is no part the gripper handles: an outline problem, a short side, no grasp, a
    yaw cue under ``MIN_YAW_CUE_M``, a preferred grasp not along x once turned to it, or a yaw the
    camera could mistake (``Prism.problems`` of the piece as cut and as turned). The draw stands or
    falls with its worst piece, so each check is made on every piece before the next, dearer one on
    any: a draw one piece's short side refuses costs no grasp search, and the yaw search (the
    dearest, and never yet the one to refuse a piece whose cue holds) runs only on a draw every
    other check passed. The same checks as piece by piece, so the same draws pass.

    ``settle_turns`` (a measured outline's, ``in_grasp_frame``): two sides a hair from parallel give
    two closing axes a hair apart, and once turned to the first the other may come first; the turn
    is then moved onto the axis that comes first, up to that many times.
    """
    if any(len(cell) < 3 for cell in cells):
        return None
    # Too wide every way, judged on the cells as cut (the bound is the same wherever the outline
    # stands): a large slab's draws fall on it before any piece is built and checked.
    if any(_too_wide_to_grasp(cell, gripper) for cell in cells):
        return None
    firsts = []
    for cell in cells:
        try:
            first = Prism.from_outline(cell.tolist(), height_m)  # a PlanError for an outline problem
        except PlanError:
            if outline_problem(cell.tolist()) is None:
                raise  # not the outline's: the height's, no draw would mend it
            return None
        if first.size_problems():
            return None
        firsts.append(first)
    # The half turn alone, before any grasp search: a long slab's pieces fall on it, at a fortieth of the cost.
    if any(float(_misfit_m(first, HALF_TURN)[0]) < MIN_YAW_CUE_M - CUE_SCREEN_MARGIN_M for first in firsts):
        return None
    # The widest piece first: the one a draw of large pieces fails on, before the others' searches.
    if not all(first.grasps(gripper) for first in sorted(firsts, key=_least_width_m, reverse=True)):
        return None
    if any(yaw_cue_m(first) < MIN_YAW_CUE_M for first in firsts):
        return None
    framed = []
    for first in firsts:
        turn = first.grasps(gripper)[0].yaw_offset_rad
        prism = _turned(first, turn, height_m)
        for _ in range(settle_turns):
            preferred = prism.grasps(gripper)
            if not preferred or preferred[0].axis == "x" or abs(math.sin(preferred[0].yaw_offset_rad)) > SETTLE_SIN:
                break
            turn += preferred[0].yaw_offset_rad
            prism = _turned(first, turn, height_m)
        if prism.size_problems() or not prism.grasps(gripper) or prism.grasps(gripper)[0].axis != "x":
            return None
        framed.append((prism, turn))
    if any(
        first.problems(gripper) or prism.problems(gripper) for first, (prism, _) in zip(firsts, framed, strict=True)
    ):
        return None
    return framed


def _turned(first: Prism, turn: float, height_m: float) -> Prism:
    c, s = math.cos(turn), math.sin(turn)
    turned = first.outline_m @ np.array([[c, -s], [s, c]])  # each point turned by -turn
    return Prism.from_outline(turned.tolist(), height_m)


#: How far from the frame's x a measured outline's preferred axis may come out to be settled onto it (1 deg).
SETTLE_SIN = math.sin(math.radians(1.0))


def in_grasp_frame(outline: FloatArray, height_m: float, gripper: Gripper = ROBOTIQ_2F85) -> tuple[Prism, float] | None:
    """One outline as a fresco's piece (``_judged`` of it alone): the prism in its grasp's frame and that frame's turn.

    None when it is no part the gripper handles. A puzzle's solved piece is framed so.
    """
    judged = _judged([np.asarray(outline, dtype=float)], height_m, gripper, settle_turns=3)
    return judged[0] if judged is not None else None


def fracture(
    size_m: tuple[float, float, float],
    pieces: int,
    gap_m: float,
    seed: int,
    pose: tuple[float, float, float] = (0.0, 0.0, 0.0),
    gripper: Gripper = ROBOTIQ_2F85,
    piece_limits: tuple[int, int] = (MIN_PIECES, MAX_PIECES),
) -> list[Piece]:
    """The slab ``size_m = (length, width, height)`` broken into ``pieces`` with ``gap_m`` along each fracture.

    ``pose`` (x, y, yaw) is where the whole goes on the table. The same arguments give the same
    pieces. A ``PlanError`` says why when no draw within ``MAX_DRAWS`` gives pieces the gripper
    can all handle. ``piece_limits`` are the fewest and most pieces (a fresco's; a puzzle's are its own).
    """
    length, width, height = size_m
    if not piece_limits[0] <= pieces <= piece_limits[1]:
        raise PlanError(f"{pieces} pieces: a fresco breaks into {piece_limits[0]} to {piece_limits[1]}")
    if gap_m < MIN_GAP_M - 1e-12:
        raise PlanError(f"a gap of {gap_m * 1000:g} mm is under the {MIN_GAP_M * 1000:g} mm two parts need")
    half_l, half_w = length / 2, width / 2
    x0, y0, yaw0 = pose
    c0, s0 = math.cos(yaw0), math.sin(yaw0)
    for draw in range(MAX_DRAWS):
        rng = np.random.default_rng([seed, draw])
        sites = _sites(rng, pieces, half_l, half_w)
        cells = _cells(sites, half_l, half_w, gap_m / 2)
        framed = _judged(cells, height, gripper)
        if framed is None:
            continue
        result = []
        for index, (cell, (prism, turn)) in enumerate(zip(cells, framed, strict=True), start=1):
            cx, cy = _area_centroid(cell)
            result.append(
                Piece(
                    index,
                    prism,
                    x0 + c0 * cx - s0 * cy,
                    y0 + s0 * cx + c0 * cy,
                    math.atan2(math.sin(yaw0 + turn), math.cos(yaw0 + turn)),
                    cell,
                )
            )
        # Pieces in a fixed order: along the slab's length, then across it.
        return _numbered(result)
    raise PlanError(
        f"no fracture of a {length * 1000:g} x {width * 1000:g} mm slab into {pieces} pieces gives pieces the "
        f"{gripper.name.split()[-1]} can all grasp (each at most {gripper.max_grasp_width_m * 1000:.0f} mm across "
        f"its grasp, sides of 10 mm or more) in {MAX_DRAWS} draws: ask for fewer pieces or a larger slab"
    )


def _numbered(pieces: list[Piece]) -> list[Piece]:
    ordered = sorted(pieces, key=lambda p: (round(float(np.mean(p.slab_outline_m[:, 0])), 4), p.index))
    return [Piece(k, p.prism, p.x_m, p.y_m, p.yaw_rad, p.slab_outline_m) for k, p in enumerate(ordered, start=1)]


def polygon_gap_m(first: FloatArray, second: FloatArray) -> float:
    """The least distance between two polygons' boundaries (N x 2 each; 0 when their edges cross)."""

    def point_segment(p: FloatArray, a: FloatArray, b: FloatArray) -> float:
        d = b - a
        t = max(0.0, min(1.0, float((p - a) @ d) / float(d @ d)))
        return float(np.hypot(*(p - a - t * d)))

    best = math.inf
    for one, other in ((first, second), (second, first)):
        count = len(other)
        for p in one:
            for k in range(count):
                best = min(best, point_segment(p, other[k], other[(k + 1) % count]))
    return best


__all__ = ["MAX_PIECES", "MIN_GAP_M", "MIN_PIECES", "Piece", "fracture", "polygon_gap_m"]
