"""A neighbour in the way of a push: which one, and how it is moved aside and put back.

Among neighbours a part is pushed only from its free sides (``free_push_directions``); where the one
push that closes its offset is blocked, ``blocked_by`` names the placed parts in that push's pads'
way. When only one neighbour is, ``move_aside`` plans what a person would do: push that neighbour
away along one of its own free square pushes, far enough that the pads' sweep
(``push_pads``) no longer meets it, with nothing of the placed parts on its way there; then,
the part corrected, push it back by a push from the side it went to, and correct it as before.
Planar geometry at the targets only, as the rest of the layout: the parts not placed yet lie where
the camera found them, unknown to the plan, and the way aside is checked against the placed parts
only.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from bt_arrange.plan.footprints import Footprint
from bt_arrange.plan.layout import Pads, push_pads
from bt_arrange.plan.layout_judged import blockers
from bt_arrange.plan.layout_part import Part

#: How far (m) past what clears the pads' sweep the neighbour is pushed: the pushes' own error.
ASIDE_MARGIN_M = 0.003
#: The longest push aside (m). In the five-piece fresco the blocked pushes a lone neighbour leaves no
#: room for took it 64 and 74.5 mm (the first piece, out of the slab along its free border): the pads'
#: sweep starts 10 mm behind the edge and is as wide as the opening, so a neighbour goes its whole width.
MAX_ASIDE_M = 0.075
#: The steps (m) the way aside is checked at.
ASIDE_STEP_M = 0.0005
#: What the neighbour keeps from every placed part on its way aside and back (m).
ASIDE_CLEARANCE_M = 0.001
#: The push back must head within this of the way back (rad): what it leaves across is the correction's.
MAX_BACK_ANGLE_RAD = math.radians(25.0)


@dataclass(frozen=True)
class MoveAside:
    """How the neighbour in the way of ``towards`` (a push of the part) is pushed aside and brought back.

    ``aside`` is the neighbour's square push (its name, ``"@114.3"``) that moves it ``distance_m``
    away; ``back`` the one that brings it back, from the side it went to.
    """

    towards: str
    neighbour: str
    aside: str
    distance_m: float
    back: str


def blocked_by(part: Part, placed: Sequence[tuple[str, Footprint]], pads: Pads) -> dict[str, tuple[str, ...]]:
    """Per push of ``part`` (at its target) that is not free, the placed parts in its pads' way."""
    others = [(n, r) for n, r in placed if n != part.name]
    out: dict[str, tuple[str, ...]] = {}
    for towards in part.push_directions:
        names = blockers([push_pads(part, part.footprint, towards, 0.0, pads)], others, pads.pad_clearance_m)
        if names:
            out[towards] = tuple(names)
    return out


def _moved(part: Part, towards: str, distance_m: float) -> Footprint:
    ux, uy = part.push_vector(towards)
    return part.footprint.moved(ux * distance_m, uy * distance_m)


def move_aside(
    part: Part, placed: Sequence[Part], pads: Pads, blocked: dict[str, tuple[str, ...]] | None = None
) -> tuple[MoveAside, ...]:
    """For each blocked push of ``part`` that one neighbour alone blocks, how to move that neighbour aside.

    ``placed`` are the parts on the table (at their targets), ``part`` among them or not. The
    neighbour's push aside must be free (its pads meet nothing placed, over the whole push), its way
    must keep ``ASIDE_CLEARANCE_M`` from every placed part, it must end clear of the part's pads
    (``ASIDE_MARGIN_M`` to spare), and a push back must be free from where it ends. The shortest
    such push; none when there is none.
    """
    footprints = [(p.name, p.footprint) for p in placed]
    by_name = {p.name: p for p in placed}
    blocked = blocked_by(part, footprints, pads) if blocked is None else blocked
    everything = footprints + ([] if part.name in by_name else [(part.name, part.footprint)])
    moves = []
    for towards, names in blocked.items():
        if len(names) != 1 or names[0] not in by_name:
            continue
        neighbour = by_name[names[0]]
        if not neighbour.by_outline:
            continue  # a box beside it: its own restaging, not this
        sweep = push_pads(part, part.footprint, towards, 0.0, pads)
        best = _aside(neighbour, sweep, [(n, r) for n, r in everything if n != neighbour.name], pads)
        if best is not None:
            moves.append(MoveAside(towards, neighbour.name, *best))
    return tuple(moves)


def _aside(
    neighbour: Part, sweep: Footprint, others: list[tuple[str, Footprint]], pads: Pads
) -> tuple[str, float, str] | None:
    """The neighbour's shortest free push that clears ``sweep``, and the push back: (aside, distance, back)."""
    best: tuple[str, float, str] | None = None
    steps = int(round(MAX_ASIDE_M / ASIDE_STEP_M))
    for aside in neighbour.push_directions:
        if blockers([push_pads(neighbour, neighbour.footprint, aside, 0.0, pads)], others, pads.pad_clearance_m):
            continue
        clear_m = None
        for k in range(1, steps + 1):
            distance_m = k * ASIDE_STEP_M
            at = _moved(neighbour, aside, distance_m)
            if blockers([at], others, ASIDE_CLEARANCE_M):
                break
            if not blockers([sweep], [(neighbour.name, at)], pads.pad_clearance_m):
                clear_m = distance_m
                break
        if clear_m is None:
            continue
        distance_m = clear_m + ASIDE_MARGIN_M
        if distance_m > MAX_ASIDE_M:
            continue
        at = _moved(neighbour, aside, distance_m)
        if blockers([at], others, ASIDE_CLEARANCE_M) or blockers(
            [push_pads(neighbour, neighbour.footprint, aside, distance_m, pads)], others, pads.pad_clearance_m
        ):
            continue
        heading = neighbour.push_heading_rad(aside) + math.pi
        backs = [
            name
            for name in neighbour.push_directions
            if abs(math.remainder(neighbour.push_heading_rad(name) - heading, math.tau)) <= MAX_BACK_ANGLE_RAD
            and not blockers([push_pads(neighbour, at, name, distance_m, pads)], others, pads.pad_clearance_m)
        ]
        if not backs:
            continue
        back = min(backs, key=lambda name: abs(math.remainder(neighbour.push_heading_rad(name) - heading, math.tau)))
        if best is None or distance_m < best[1]:
            best = (aside, distance_m, back)
    return best
