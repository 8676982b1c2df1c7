"""Where a square push of an irregular part goes: which edge, how far, how far across, or what blocks it.

Pure planning on the offset (mm, the target's frame) and the part's named square pushes
(``Shape.named_pushes``), for ``Push``: no motion, no blackboard. Among neighbours (some pushes
not free) a long push stops short and a push may also move the part across.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from bt_arrange.plan.layout_part import pushed_from
from bt_arrange.shapes import SquarePush

#: Strategy "diagonal": the most a push may move the part across its axis, per millimetre along it.
#: The pads drag the part sideways by friction (pads 1.2 on the part: slipping only beyond about
#: 50 deg, atan 1.2); 0.6 (31 deg) keeps well inside that and the line contact squares the part.
DIAGONAL_ACROSS_RATIO = 0.6


#: Among neighbours an offset at most this long (mm) between two free pushes is closed by both.
CONE_MAX_OFFSET_MM = 2.0
#: ... when the two pushes travel no more than this many times the offset together (headings up to
#: 151 deg apart with the offset halfway between them; a triangle's +x and hypotenuse pushes, 135 deg
#: apart, travel 2.1 times theirs). Two pushes nearly opposite take any offset between them by
#: travelling far: a fresco piece 1.19 mm off, between pushes 178.9 deg apart, was pushed 59.5 mm
#: into two neighbours (tight gaps, seed 25), 100 times its offset.
CONE_MAX_TRAVEL_RATIO = 4.0
#: Among neighbours a square push longer than this (mm; a staged part's way home) stops
#: ``APPROACH_RESERVE_MM`` short of the target: its pads can still move it across the push then.
#: Pushed all the way, the part landed 0.2 to 0.35 mm beside its place (the squaring contact turns
#: it about the pads), on a side only a blocked push reaches.
LONG_PUSH_MM = 3.0
#: The least a long push among neighbours may move a part across on its way (mm; named when it
#: was the most for a turned part).
LONG_PUSH_MAX_ACROSS_MM = 1.0
#: A long push moves the part across by up to this much of its length (at least
#: ``LONG_PUSH_MAX_ACROSS_MM``; 0.25 is 14 deg, inside ``DIAGONAL_ACROSS_RATIO``), however turned:
#: in the calibrated real-cell model pieces land 4 to 6 mm beside their staging's line, and one pushed
#: home 32 mm with 1 mm across ended 2.6 mm beside its place, against a neighbour on the side only a
#: blocked push reaches. ``benchmarks/long_push.py`` (three fresco tiles, 20 mm pushes, turned 0.5
#: to 3 deg, 1 to 4 mm beside): every piece squared, 118 of 120 within 0.5 mm (the others 0.55 and
#: 0.66 mm); held to 1 mm across, as a turned part was before, 10 of 40 (up to 4.3 mm off).
LONG_PUSH_ACROSS_RATIO = 0.25
#: How far short of the target a long push among neighbours stops (mm): enough along the push for
#: ``DIAGONAL_ACROSS_RATIO`` of it to carry the part across by what the long push left beside it.
APPROACH_RESERVE_MM = 1.0
#: A push stops short of the place only by this many thresholds or more: the correction must go on
#: (at the example fresco's 0.8 mm, pieces left 0.4 mm short were within, and the next piece's
#: set-down met one of them).
STOP_SHORT_FACTOR = 1.5
#: Near the target, a push that must also move the part this far across or more (mm) ...
SLANT_STEP_ACROSS_MM = 0.15
#: ... stops this far short of the place (mm), when it can: the last push along closes what it left across.
SLANT_STEP_RESERVE_MM = 0.4
#: A push that also moves the part across comes straight up to this far (mm) before the edge's
#: place, then turns to its slanted line: the pads move across the push only near the edge, so they
#: keep to the side of the part they were checked on.
SLANT_RUN_IN_MM = 1.0
#: A squaring push of an irregular part presses its edge this far past where it belongs: a push
#: that only reaches the edge's place leaves a part turned 1 deg barely touched (measured: ten
#: such pushes left a fresco piece 1.27 deg off).
SQUARING_PRESS_MM = 0.3


def long_push_across_limit_mm(distance_mm: float) -> float:
    """The most a long push among neighbours of ``distance_mm`` moves the part across (before the friction cone).

    ``LONG_PUSH_ACROSS_RATIO`` of the push, at least ``LONG_PUSH_MAX_ACROSS_MM``, whatever the part's
    turn (the push squares it on the way: the swing it predicts is taken off beforehand,
    ``squaring_shift_mm``).
    """
    return max(LONG_PUSH_MAX_ACROSS_MM, LONG_PUSH_ACROSS_RATIO * distance_mm)


def plan_square_push(
    offset_xy_mm: tuple[float, float],
    pushes: dict[str, SquarePush],
    towards: tuple[str, ...],
    min_push_mm: float,
    turned: bool,
    threshold_mm: float | None = None,
    yaw_error_rad: float = 0.0,
    among_neighbours: bool | None = None,
) -> SquareMove | Blocked | None:
    """``choose_square_push``, and among neighbours a long push stopped short or a push that also moves across.

    With a neighbour beside the part (a push not in ``towards``):

    - a push longer than ``LONG_PUSH_MM`` (a staged part on its way home) stops
      ``APPROACH_RESERVE_MM`` short of the target, its pads moving the part across onto the
      target's line as they go (below);
    - near the target (``LONG_PUSH_MM``) an offset is closed by one free push whose pads
      also move across it by what lies beside it, at most ``DIAGONAL_ACROSS_RATIO`` of the
      push's length (the part follows them by friction), the squarest such push: the part goes
      straight to its place. Pushed by its projection alone, it would be left beside its place,
      on a side only a blocked push may reach; by two pushes (``_free_cone_shares``), past its
      place on the way (a piece 1 mm from home was pushed 2.2 mm, past it into a neighbour
      0.5 mm away). Only when no one push closes it: two free pushes that take it between
      them, else the push that leaves the least beside the place.

    A push stops short only by what leaves the part ``STOP_SHORT_FACTOR`` times ``threshold_mm``
    or more from its place, so that the correction goes on (None: never): at a coarse threshold
    it would end there, short, and what it corrects (0.2 to 0.35 mm beside the place) is within.

    A long push among neighbours (``among_neighbours``: a staged part, whose pushes may all be
    free; None: some push is blocked), at any threshold, moves the part across onto its target's
    line, less what squaring it will carry it across (``squaring_shift_mm``, from ``yaw_error_rad``,
    the part's measured yaw less its target's). Otherwise, every push free: ``choose_square_push``'s
    choice, as it is.
    """
    choice = choose_square_push(offset_xy_mm, pushes, towards, min_push_mm, turned)
    plain = SquareMove(*choice) if isinstance(choice, tuple) else choice
    free = [name for name in pushes if name in towards]

    def may_stop_short(reserve_mm: float) -> bool:
        return threshold_mm is not None and reserve_mm >= STOP_SHORT_FACTOR * threshold_mm

    if not free:
        return plain
    some_blocked = len(free) < len(pushes)
    offset = np.asarray(offset_xy_mm, dtype=float)
    if (some_blocked if among_neighbours is None else among_neighbours) and (
        isinstance(plain, SquareMove) and plain.distance_mm > LONG_PUSH_MM
    ):
        # On the way home the pads also bring the part onto its place's line (a set-down 0.7 mm
        # beside it stayed so): they end on the line the layout checked them along, at most
        # long_push_across_limit_mm. With a push blocked, at a fine threshold, it stops short, for
        # the next push to close the rest.
        reserve_mm = APPROACH_RESERVE_MM if some_blocked and may_stop_short(APPROACH_RESERVE_MM) else 0.0
        push = pushes[plain.name]
        beside = float(offset @ np.array([-math.sin(push.heading_rad), math.cos(push.heading_rad)]))
        beside -= squaring_shift_mm(push, yaw_error_rad)
        distance = plain.distance_mm - reserve_mm
        limit = min(DIAGONAL_ACROSS_RATIO * distance, long_push_across_limit_mm(distance))
        across = max(-limit, min(limit, beside)) if abs(beside) >= min_push_mm else 0.0
        return SquareMove(plain.name, distance, across)
    if not some_blocked:
        return plain
    if not may_stop_short(APPROACH_RESERVE_MM):
        # A coarse threshold: what the pushes below correct is mostly within, and the example fresco
        # (0.8 mm) went as before, not better. Only near the target, where the push by the projection
        # would leave the part more than half the threshold beside its place, on a side no free push
        # reaches, a free push that also moves it across leaves less there (a fresco piece pushed home
        # 15 mm landed 1 mm beside its place; pushed along, it was left 1.07 mm from it, blocked).
        left = _left_by(offset, pushes, plain) if isinstance(plain, SquareMove) else None
        beside = math.inf if left is None else float(np.hypot(*left))
        if (
            left is not None
            and threshold_mm is not None
            and float(np.hypot(*offset)) <= LONG_PUSH_MM
            and beside > threshold_mm / 2
            and isinstance(
                choose_square_push((float(left[0]), float(left[1])), pushes, towards, min_push_mm, False), Blocked
            )
        ):
            better = [item for item in _slanted(offset, pushes, free, min_push_mm) if item[0] < beside - min_push_mm]
            if better:
                return min(better, key=lambda item: item[:2])[2]
        return plain
    if float(np.hypot(*offset)) > LONG_PUSH_MM:
        # Between CONE_MAX_OFFSET_MM and here too: a piece turned 2 deg at its set-down ended its long
        # push 2.2 mm short, 0.75 mm beside its line, and its push by the projection met a neighbour.
        return plain
    if isinstance(plain, SquareMove) and plain.distance_mm < min_push_mm:  # a squaring press
        return plain
    slanted = _slanted(offset, pushes, free, min_push_mm)
    exact = [item for item in slanted if item[0] == 0.0]
    if exact:
        # One push straight to the target, the squarest one: the part never passes its place.
        move = min(exact, key=lambda item: item[1])[2]
        shorter = move.distance_mm - SLANT_STEP_RESERVE_MM
        if (
            may_stop_short(SLANT_STEP_RESERVE_MM)
            and SLANT_STEP_ACROSS_MM <= abs(move.across_mm) <= DIAGONAL_ACROSS_RATIO * shorter
        ):
            # Far across: onto the target's line first, short of the place, so that what that leaves
            # across is closed by the last push along.
            return SquareMove(move.name, shorter, move.across_mm)
        return move
    if _free_cone_shares(offset, pushes, free) is not None or not slanted:
        return plain
    return min(slanted, key=lambda item: item[:2])[2]


def squaring_shift_mm(push: SquarePush, yaw_error_rad: float) -> float:
    """How far (mm, to the push's left) a push that squares a part turned ``yaw_error_rad`` carries it across.

    The pads meet the leading corner of the edge first; the part turns square about that corner,
    which the pads' friction holds, and its centroid, ``back_m`` ahead of the edge, swings across.
    Measured on the example fresco's long pushes (seed 0): pieces turned -1.33, -1.30, -0.87 and
    +0.49 deg went 0.62, 0.60, 0.40 and -0.34 mm to the left, 26, 26, 26 and 40 mm times their turn;
    the edges lie 26.6, 25.8, 25.1 and 39.8 mm behind their centroids.
    """
    return -yaw_error_rad * push.back_m * 1000


def _left_by(offset: np.ndarray, pushes: dict[str, SquarePush], move: SquareMove) -> np.ndarray:
    """The offset (mm) a push leaves: what it does not close along its heading, less what it moves across."""
    heading = pushes[move.name].heading_rad
    along = np.array([math.cos(heading), math.sin(heading)])
    left = np.array([-math.sin(heading), math.cos(heading)])
    return offset - move.distance_mm * along - move.across_mm * left


def _slanted(
    offset: np.ndarray, pushes: dict[str, SquarePush], free: list[str], min_push_mm: float
) -> list[tuple[float, float, SquareMove]]:
    """Each free push by the offset's projection, its pads moving across by what lies beside it.

    At most ``DIAGONAL_ACROSS_RATIO`` of the push across; each as (what it leaves beside the place
    (mm), across per along, the move).
    """
    slanted: list[tuple[float, float, SquareMove]] = []
    for name in free:
        heading = pushes[name].heading_rad
        along = float(offset @ np.array([math.cos(heading), math.sin(heading)]))
        if along < min_push_mm:
            continue
        beside = float(offset @ np.array([-math.sin(heading), math.cos(heading)]))
        limit = DIAGONAL_ACROSS_RATIO * along
        across = max(-limit, min(limit, beside)) if abs(beside) >= min_push_mm else 0.0
        left = abs(beside - across) if abs(beside) >= min_push_mm else 0.0
        slanted.append((left, abs(across) / along, SquareMove(name, along, across)))
    return slanted


def choose_square_push(
    offset_xy_mm: tuple[float, float],
    pushes: dict[str, SquarePush],
    towards: tuple[str, ...],
    min_push_mm: float,
    turned: bool,
) -> tuple[str, float] | Blocked | None:
    """Which square push to make and how far (mm), what blocks the one needed, or None: nothing to push.

    The offset (target minus pose, target frame) is projected on each push's heading: the
    push that closes most of it, among the free ones (``towards``), is made by that
    projection; what it leaves lies across it, for the next push. When the best push is
    below ``min_push_mm`` a part ``turned`` past the yaw threshold is still pushed on the
    free edge the pads stand widest on, ``SQUARING_PRESS_MM`` past where that edge belongs: the square contact
    turns it back. When only blocked pushes close the offset: ``Blocked`` with the best of them.
    """
    offset = np.asarray(offset_xy_mm, dtype=float)
    along = {
        name: float(offset @ np.array([math.cos(p.heading_rad), math.sin(p.heading_rad)])) for name, p in pushes.items()
    }
    free = [name for name in pushes if name in towards]
    best = max(pushes, key=lambda name: along[name])
    if len(free) < len(pushes) and float(np.hypot(*offset)) <= CONE_MAX_OFFSET_MM:
        # Among neighbours a push by the whole projection can carry the part past the line of a
        # second free push, into a place only a blocked push would close. Two free pushes whose
        # headings take the offset between them close it exactly, each by its own share; near
        # the target only, where the pads' way is the one the layout checked (a staged part far
        # from it goes home by the push its staging chose).
        shares = _free_cone_shares(offset, pushes, free)
        if shares is not None:
            chosen, distance_mm = max(shares, key=lambda share: share[1])
            if distance_mm >= min_push_mm:
                return chosen, distance_mm
    usable = [name for name in free if along[name] >= min_push_mm]
    if usable:
        chosen = max(usable, key=lambda name: along[name])
        return chosen, along[chosen]
    if along[best] >= min_push_mm:
        return Blocked(best, along[best])
    if turned and free:
        widest = max(free, key=lambda name: (pushes[name].opening_m, pushes[name].edge_m))
        # Pressed a little past where the edge belongs, so that the pads meet all of it there.
        return widest, max(0.0, along[widest]) + SQUARING_PRESS_MM
    return None


def cone_push(
    offset_xy_mm: tuple[float, float], pushes: dict[str, SquarePush], towards: tuple[str, ...], min_push_mm: float
) -> tuple[str, float] | None:
    """The larger share of the two free pushes whose headings take the offset between them (mm), or None.

    For a part among neighbours whose offset no one square push closes (it lies across all of
    them): the next push after this one closes the rest. None when no two free pushes take it
    between them, or the larger share is below ``min_push_mm``.
    """
    shares = _free_cone_shares(np.asarray(offset_xy_mm, dtype=float), pushes, [n for n in pushes if n in towards])
    if shares is None:
        return None
    chosen, distance_mm = max(shares, key=lambda share: share[1])
    return (chosen, distance_mm) if distance_mm >= min_push_mm else None


@dataclass(frozen=True)
class SquareMove:
    """A square push: which (``Prism.named_pushes``' name), how far along its heading, how far across (mm).

    ``across_mm`` is positive to the left of the heading (the heading turned by +90 deg): the pads
    move that far sideways while they press the edge, and the part follows them by friction.
    """

    name: str
    distance_mm: float
    across_mm: float = 0.0


@dataclass(frozen=True)
class Blocked:
    """A correction Push cannot make: the part must move ``towards`` (target frame) by ``offset_mm``."""

    towards: str
    offset_mm: float
    #: Nothing blocks it: the offset lies across every square push, and no two take it between them.
    across_every_push: bool = False

    def reason(self, obj: str, neighbour: str | None = None) -> str:
        """The feedback: which side, and which neighbour (None: "a neighbour") leaves the pads no room."""
        if self.across_every_push:
            return (
                f"{obj} needs a push of {abs(self.offset_mm):.2f} mm across every square push it has, and no "
                "two take it between them: among neighbours no other push is made"
            )
        who = neighbour or "a neighbour"
        if self.towards.startswith("@"):
            return (
                f"{obj} needs a push of {abs(self.offset_mm):.2f} mm squarely towards {self.towards[1:]} deg (its "
                f"frame), where {who} leaves the pads no room, and no free push closes it"
            )
        side = pushed_from(self.towards)
        return (
            f"{obj} needs a push of {abs(self.offset_mm):.2f} mm towards {self.towards}, from its {side} side, "
            f"where {who} leaves the pads no room"
        )


def _free_cone_shares(
    offset_mm: np.ndarray, pushes: dict[str, SquarePush], free: list[str]
) -> list[tuple[str, float]] | None:
    """The two free pushes (and how far each, mm) whose headings take the offset between them, or None.

    ``offset = a u + b v`` with ``a, b >= 0`` for the headings ``u``, ``v`` of two free pushes less than
    half a turn apart; of all such pairs, the one that travels least (``a + b``), and none that
    travels more than ``CONE_MAX_TRAVEL_RATIO`` times the offset.
    """
    best: tuple[float, list[tuple[str, float]]] | None = None
    for i, first in enumerate(free):
        u = np.array([math.cos(pushes[first].heading_rad), math.sin(pushes[first].heading_rad)])
        for second in free[i + 1 :]:
            v = np.array([math.cos(pushes[second].heading_rad), math.sin(pushes[second].heading_rad)])
            determinant = float(u[0] * v[1] - u[1] * v[0])
            if abs(determinant) < 1e-6:  # parallel or opposite: no cone
                continue
            a = float(offset_mm[0] * v[1] - offset_mm[1] * v[0]) / determinant
            b = float(u[0] * offset_mm[1] - u[1] * offset_mm[0]) / determinant
            if a < 0.0 or b < 0.0 or a + b > CONE_MAX_TRAVEL_RATIO * float(np.hypot(*offset_mm)):
                continue
            if best is None or a + b < best[0]:
                best = (a + b, [(first, a), (second, b)])
    return None if best is None else best[1]
