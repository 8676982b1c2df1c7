"""Where the pads come down among neighbours when the part sits along them off where the pick meant.

The layout plans a release among neighbours with the pads at the part's grasp centre
(``release_pads``). A part measured in the fingers (``LookAtHeld``) is placed by moving
the TCP so that the part lands where the layout put it; but the pads move with the TCP. Along the
closing axis that changes nothing (the pads hold the part's sides wherever it sits between them);
along the pads' width, a grasp some millimetres off slides both pads that far along the part's
sides, where the layout never checked them: in the calibrated real-cell model (the arm's
kinematic error where the part was picked) 4 to 7 mm, enough for a finger to come down on a
neighbour 2 mm away and flip it out of the slab.

``ReleaseRoom`` is what the layout knew when it chose the release (the part, its staging, the
parts then placed, the pads) and ``ReleaseRoom.settle`` splits the measured slide: the TCP
follows it as far as the pads stay clear of every placed part, and the rest is left to the part,
which lands that much off its staging along the pads, provided it keeps its own room there
(``Pads.place_clearance_m``). A part released among neighbours is looked at and pushed home from
where it lands, so landing off its staging along the pads costs at most a longer push. Without such a
split (no room for either) the slide is followed whole, as before.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol

from bt_arrange.plan.footprints import Footprint, Rect
from bt_arrange.plan.layout_judged import blockers
from bt_arrange.plan.layout_part import Part


class PadFigures(Protocol):
    """What the release needs of ``layout.Pads`` (the layout imports this module: no import back)."""

    @property
    def release_gap_m(self) -> float: ...  # noqa: D102 - Pads'

    @property
    def finger_depth_m(self) -> float: ...  # noqa: D102 - Pads'

    @property
    def place_clearance_m(self) -> float: ...  # noqa: D102 - Pads'

    @property
    def width_m(self) -> float: ...  # noqa: D102 - Pads'

    @property
    def pad_clearance_m(self) -> float: ...  # noqa: D102 - Pads'


class Released(Protocol):
    """What the room needs of ``layout.Release``: the closing axis and where the part's origin is let go."""

    @property
    def axis(self) -> str: ...  # noqa: D102 - Release's

    @property
    def staging_m(self) -> tuple[float, float]: ...  # noqa: D102 - Release's


def release_pads(part: Part, at: Footprint, axis: str, pads: PadFigures) -> list[Rect]:
    """The two rectangles the pads sweep holding, lowering and releasing ``part`` at ``at`` across ``axis``."""
    half = part.grasp_half(axis)
    cx, cy = part.grasp_centre(axis)
    depth = pads.release_gap_m + pads.finger_depth_m
    centre = half + depth / 2
    if axis == "x":
        return [at.local(cx + sign * centre, cy, depth / 2, pads.width_m / 2) for sign in (1, -1)]
    return [at.local(cx, cy + sign * centre, pads.width_m / 2, depth / 2) for sign in (1, -1)]


#: The slides tried between the measured one and none, this far apart (m).
SLIDE_STEP_M = 0.00025


@dataclass(frozen=True)
class Settled:
    """How a measured slide along the pads is split between the TCP and the part.

    ``tcp_slide_m``: how far the TCP follows the slide (the pads move that far along the part's
    sides); ``part_off_m``: how far the part lands off its staging along the pads (``tcp_slide_m``
    less the slide); ``kept_off``: the placed parts the whole slide would have brought a pad onto
    (empty when the slide is followed whole).
    """

    tcp_slide_m: float
    part_off_m: float
    kept_off: tuple[str, ...] = ()


@dataclass(frozen=True)
class ReleaseRoom:
    """A release's neighbourhood as the layout saw it: the part, its release, the parts placed before it."""

    part: Part
    release: Released
    placed: tuple[tuple[str, Footprint], ...]
    pads: PadFigures

    def along_pads(self) -> tuple[float, float]:
        """The pads' width direction in the target's frame (across the closing axis)."""
        return (0.0, 1.0) if self.release.axis == "x" else (1.0, 0.0)

    def along_pads_world(self, target_yaw_rad: float) -> tuple[float, float]:
        """The pads' width direction on the table, for a target turned ``target_yaw_rad``."""
        ux, uy = self.along_pads()
        c, s = math.cos(target_yaw_rad), math.sin(target_yaw_rad)
        return (c * ux - s * uy, s * ux + c * uy)

    def _staged(self, slide_m: float) -> Footprint:
        ux, uy = self.along_pads()
        sx, sy = self.release.staging_m
        return self.part.footprint.moved(sx + ux * slide_m, sy + uy * slide_m)

    def pads_meet(self, slide_m: float) -> list[str]:
        """The placed parts the pads meet, slid ``slide_m`` along the part's sides from where the layout put them."""
        pads = release_pads(self.part, self._staged(slide_m), self.release.axis, self.pads)
        return blockers(pads, self.placed, self.pads.pad_clearance_m)

    def part_meets(self, off_m: float) -> list[str]:
        """The placed parts the part meets, landed ``off_m`` along the pads from its staging."""
        return blockers([self._staged(off_m)], self.placed, self.pads.place_clearance_m)

    def settle(self, slide_m: float) -> Settled:
        """The split of a measured ``slide_m`` nearest following it whole with the pads and the part both clear."""
        kept_off = tuple(self.pads_meet(slide_m))
        if not kept_off:
            return Settled(slide_m, 0.0)
        steps = math.ceil(abs(slide_m) / SLIDE_STEP_M)
        for k in range(1, steps + 1):
            # From the whole slide back towards none (the pads where the layout put them).
            tcp_slide_m = slide_m * (1.0 - k / steps)
            off_m = tcp_slide_m - slide_m
            if not self.pads_meet(tcp_slide_m) and not self.part_meets(off_m):
                return Settled(tcp_slide_m, off_m, kept_off)
        return Settled(slide_m, 0.0)


def release_room(
    part: Part, release: Released, placed: Sequence[tuple[str, Footprint]], pads: PadFigures
) -> ReleaseRoom | None:
    """The room of a release among ``placed`` parts (at its target or staged); None with none placed."""
    if not placed:
        return None
    return ReleaseRoom(part, release, tuple(placed), pads)
