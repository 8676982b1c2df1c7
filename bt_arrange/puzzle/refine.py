"""An assembly fitted as a whole: every piece's pose adjusted at once to its contacts, and its misfits.

The search places cells one after another; each place then carries the errors of the ones before.
Here the measured outlines themselves are fitted: along every fracture two pieces' edges face each
other (antiparallel) the gap apart, and every border edge lies on its side of the rectangle. The
contacts are found from the search's poses, then all poses are fitted to them by least squares
(each contact's overlap ends, on both edges); the RMS of the misfits is the assembly's residual.
With colour samples, the colour misfit across the fractures is measured too.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from bt_arrange.geometry import FloatArray
from bt_arrange.puzzle.shapes import Shape, rotation

#: Facing edges are contacts when within this angle of antiparallel ...
CONTACT_ANGLE_RAD = math.radians(4.0)
#: ... their gap within this of the expected one, and they overlap by this much along the edge.
CONTACT_GAP_M = 0.0012
CONTACT_OVERLAP_M = 0.002
#: The pull of each pose towards the search's, per metre or radian of misfit: keeps the fit well posed.
PRIOR_WEIGHT = 1e-3
#: Colour samples of two pieces this much farther apart than the gap are not compared.
COLOUR_REACH_M = 0.002


@dataclass(frozen=True)
class Fitted:
    """Poses fitted (turn and shift per shape, in shape order), the RMS misfit and the colour misfit (or None)."""

    turns: FloatArray
    shifts: FloatArray
    residual_m: float
    colour_misfit: float | None
    contacts: int


def _sides(half_l: float, half_w: float) -> list[tuple[FloatArray, float]]:
    return [
        (np.array([0.0, -1.0]), half_w),
        (np.array([1.0, 0.0]), half_l),
        (np.array([0.0, 1.0]), half_w),
        (np.array([-1.0, 0.0]), half_l),
    ]


def _rows(
    shapes: Sequence[Shape], turns: FloatArray, shifts: FloatArray, half_l: float, half_w: float, gap: float
) -> list[tuple[int, FloatArray, int, FloatArray, FloatArray, float]]:
    """(piece, local point, other piece or -1, other's local line point, other's local normal or the side's, target)."""
    placed = [shape.points @ rotation(t).T + s for shape, t, s in zip(shapes, turns, shifts, strict=True)]
    rows: list[tuple[int, FloatArray, int, FloatArray, FloatArray, float]] = []
    cos_tol = math.cos(CONTACT_ANGLE_RAD)
    for i, shape in enumerate(shapes):
        points = placed[i]
        for k in range(shape.count):
            a, b = points[k], points[(k + 1) % shape.count]
            direction = (b - a) / float(np.hypot(*(b - a)))
            for normal, offset in _sides(half_l, half_w):
                along = np.array([-normal[1], normal[0]])
                if (
                    float(direction @ along) > cos_tol
                    and max(abs(float(normal @ a) - offset), abs(float(normal @ b) - offset)) < 2 * CONTACT_GAP_M
                ):
                    for local in (shape.points[k], shape.points[(k + 1) % shape.count]):
                        rows.append((i, local, -1, normal * offset, normal, 0.0))
            for j, other in enumerate(shapes):
                if j == i:
                    continue
                others = placed[j]
                for m in range(other.count):
                    c, d = others[m], others[(m + 1) % other.count]
                    other_dir = (d - c) / float(np.hypot(*(d - c)))
                    if float(direction @ other_dir) > -cos_tol:
                        continue
                    other_normal = np.array([other_dir[1], -other_dir[0]])  # out of the other piece
                    gaps = [float(other_normal @ (p - c)) for p in (a, b)]
                    if max(abs(g - gap) for g in gaps) > CONTACT_GAP_M:
                        continue
                    span = float((b - a) @ direction)
                    lo = max(0.0, min(float((c - a) @ direction), float((d - a) @ direction)))
                    hi = min(span, max(float((c - a) @ direction), float((d - a) @ direction)))
                    if hi - lo < CONTACT_OVERLAP_M:
                        continue
                    inverse = rotation(turns[j]).T
                    line_point = inverse @ (c - shifts[j])
                    line_normal = inverse @ other_normal
                    for fraction in (lo / span, hi / span):
                        local = shape.points[k] + fraction * (shape.points[(k + 1) % shape.count] - shape.points[k])
                        rows.append((i, local, j, line_point, line_normal, gap))
    return rows


def fit(
    shapes: Sequence[Shape],
    turns: FloatArray,
    shifts: FloatArray,
    half_l: float,
    half_w: float,
    gap: float,
) -> Fitted:
    """All poses fitted to the contacts found at the given ones."""
    rows = _rows(shapes, turns, shifts, half_l, half_w, gap)
    count = len(shapes)
    if not rows:
        return Fitted(turns, shifts, math.inf, None, 0)
    piece = np.array([r[0] for r in rows])
    local = np.array([r[1] for r in rows])
    other = np.array([r[2] for r in rows])
    line_point = np.array([r[3] for r in rows])
    line_normal = np.array([r[4] for r in rows])
    target = np.array([r[5] for r in rows])
    has_other = other >= 0
    other_index = np.where(has_other, other, 0)
    start = np.concatenate([np.asarray(turns)[:, None], np.asarray(shifts)], axis=1).ravel()

    def misfits(x: FloatArray) -> FloatArray:
        poses = x.reshape(count, 3)
        c, s = np.cos(poses[:, 0]), np.sin(poses[:, 0])
        pc, ps = c[piece], s[piece]
        px = pc * local[:, 0] - ps * local[:, 1] + poses[piece, 1]
        py = ps * local[:, 0] + pc * local[:, 1] + poses[piece, 2]
        oc, os_ = c[other_index], s[other_index]
        lx = np.where(
            has_other, oc * line_point[:, 0] - os_ * line_point[:, 1] + poses[other_index, 1], line_point[:, 0]
        )
        ly = np.where(
            has_other, os_ * line_point[:, 0] + oc * line_point[:, 1] + poses[other_index, 2], line_point[:, 1]
        )
        nx = np.where(has_other, oc * line_normal[:, 0] - os_ * line_normal[:, 1], line_normal[:, 0])
        ny = np.where(has_other, os_ * line_normal[:, 0] + oc * line_normal[:, 1], line_normal[:, 1])
        contact = nx * (px - lx) + ny * (py - ly) - target
        return np.concatenate([contact, PRIOR_WEIGHT * (x - start)])

    result = least_squares(misfits, start, method="lm", x_scale=np.tile([0.05, 1e-3, 1e-3], count))
    poses = result.x.reshape(count, 3)
    contact = misfits(result.x)[: len(rows)]
    residual = float(np.sqrt(np.mean(contact**2)))
    turns_fit, shifts_fit = poses[:, 0].copy(), poses[:, 1:].copy()
    return Fitted(turns_fit, shifts_fit, residual, colour_misfit(shapes, turns_fit, shifts_fit, gap), len(rows))


def colour_misfit(shapes: Sequence[Shape], turns: FloatArray, shifts: FloatArray, gap: float) -> float | None:
    """The mean squared RGB difference between each colour sample and the nearest one across a fracture.

    None when no piece has colour samples near another's.
    """
    places, colours, owners = [], [], []
    for i, (shape, turn, shift) in enumerate(zip(shapes, turns, shifts, strict=True)):
        if len(shape.samples):
            places.append(shape.samples @ rotation(turn).T + shift)
            colours.append(shape.colours)
            owners.append(np.full(len(shape.samples), i))
    if len(places) < 2:
        return None
    place, colour, owner = np.concatenate(places), np.concatenate(colours), np.concatenate(owners)
    distance = np.hypot(place[:, None, 0] - place[None, :, 0], place[:, None, 1] - place[None, :, 1])
    distance[owner[:, None] == owner[None, :]] = np.inf
    nearest = np.argmin(distance, axis=1)
    close = distance[np.arange(len(place)), nearest] <= gap + COLOUR_REACH_M
    if not np.any(close):
        return None
    difference = colour[close] - colour[nearest[close]]
    return float(np.mean(np.sum(difference**2, axis=1)))


def fit_step(rows: list[tuple[FloatArray, FloatArray, float]], centre: FloatArray) -> tuple[float, FloatArray] | None:
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
    return float(solution[0]), np.asarray(solution[1:], dtype=float)


__all__ = ["Fitted", "colour_misfit", "fit", "fit_step"]
