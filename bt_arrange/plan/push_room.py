"""Sides no pad can push from: a plan's gaps, warned about before anything moves.

A push towards ``+y`` puts the pads behind the part's ``-y`` face: they start
``push_clearance_m`` behind it, are a pad's width deep and keep ``pad_clearance_m`` from a
neighbour. A part that needs that push lies short of its place, nearer the neighbour by its
placing error, and the neighbour may lie off its own place by up to the threshold. So the pads fit
only where the plan's gap is at least::

    push_clearance + pad width + pad clearance + expected placing error + threshold

(10 + 22 + 2 + 3.7 + 1 = 38.7 mm for cubes at 1 mm with the 2F-85 in the paper's real cell). Nearer,
a correction that needs that push releases the part again past its place (a cuboid's restaging)
or is made by a neighbour moved aside; at worst it ends at the best offset it measured, naming the
side and the neighbour. ``tight_sides(plan)`` lists each such side with the gap it would need; the
command line prints them as warnings before a run::

    bt-arrange: warning: blue's -y side is 30.0 mm from red, and a pad pushing blue towards +y needs 38.2 mm ...
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

from bt_arrange.plan import stacking
from bt_arrange.plan.compiled import ArrangementPlan, PartStep
from bt_arrange.plan.footprints import Footprint, gap_m
from bt_arrange.plan.layout import Pads, push_pads, restage_releases
from bt_arrange.plan.layout_judged import blockers
from bt_arrange.plan.layout_part import pushed_from

#: The placing error a plan's gaps are judged at (mm): the paper's real cell after placing with no
#: injected error, 3.72 mm (its Gazebo: 0.47 mm; FACTS.md, "A real cell's errors").
EXPECTED_PLACE_ERROR_MM = 3.7


@dataclass(frozen=True)
class TightSide:
    """A side of ``obj`` where ``neighbour`` leaves the pads no room to push ``obj`` ``towards`` (target frame)."""

    obj: str
    towards: str
    neighbour: str
    gap_mm: float
    needed_mm: float
    #: The plan blocks this push outright (its nominal gap is too narrow), not only at the expected errors.
    blocked: bool
    #: A correction that needs this push releases the part again past its place (a cuboid's restaging,
    #: with every neighbour placed).
    restaged: bool

    @property
    def side(self) -> str:
        """The side the pads push from: ``"-y"`` for a push towards ``"+y"``, a square push's name as it is."""
        side = pushed_from(self.towards)
        if side is not None:
            return side
        return f"{self.towards[1:]} deg" if self.towards.startswith("@") else self.towards

    def text(self) -> str:
        """One line: the side, the neighbour, the gap and the gap it would need."""
        push = (
            f"pushing {self.obj} towards {self.towards}"
            if len(self.towards) == 2
            else f"pushing {self.obj} squarely towards {self.side} (its frame)"
        )
        side = f"{self.obj}'s {self.side} side" if len(self.towards) == 2 else f"{self.obj}'s edge behind that push"
        then = (
            f"a correction that needs it releases {self.obj} again past its place"
            if self.restaged
            else "a correction that needs it is made another way or ends at the best offset it measured"
        )
        return (
            f"{side} is {self.gap_mm:.1f} mm from {self.neighbour}, and a pad {push} needs {self.needed_mm:.1f} mm "
            f"at the expected placing error: {then} (a gap of {self.needed_mm:.1f} mm would leave it free)"
        )


def needed_gap_mm(pads: Pads, threshold_mm: float, expected_error_mm: float = EXPECTED_PLACE_ERROR_MM) -> float:
    """The gap (mm) behind a face that leaves the pads room to push it at the expected placing error."""
    reach_mm = (pads.push_clearance_m + pads.width_m + pads.pad_clearance_m) * 1000
    return reach_mm + expected_error_mm + threshold_mm


def tight_sides(plan: ArrangementPlan, expected_error_mm: float = EXPECTED_PLACE_ERROR_MM) -> list[TightSide]:
    """Every side of every part of ``plan`` where a neighbour leaves the pads no room at ``expected_error_mm``.

    Judged in the finished arrangement (every part of a layer placed), nearest neighbour first.
    Only a compiled plan's parts are judged: a hand-built tree's plan has no steps.
    """
    pads = Pads.from_settings(plan.settings)
    needed_mm = needed_gap_mm(pads, plan.tolerance.threshold_mm, expected_error_mm)
    margin_m = (expected_error_mm + plan.tolerance.threshold_mm) / 1000
    layouts = [step for step in plan.steps if step.layout is not None]
    out: list[TightSide] = []
    for step in layouts:
        assert step.layout is not None
        part = step.layout.part
        others = _same_layer(step, layouts)
        if not others:
            continue
        restage: Mapping[str, object] | None = None
        for towards in part.push_directions:
            volume = push_pads(part, part.footprint, towards, 0.0, pads)
            near = blockers([volume], others, pads.pad_clearance_m + margin_m)
            if not near:
                continue
            footprints = dict(others)
            restage = restage_releases(part, others, pads) if restage is None else restage
            nearest = min(near, key=lambda name: gap_m(part.footprint, footprints[name]))
            out.append(
                TightSide(
                    obj=part.name,
                    towards=towards,
                    neighbour=nearest,
                    gap_mm=gap_m(part.footprint, footprints[nearest]) * 1000,
                    needed_mm=needed_mm,
                    blocked=bool(blockers([volume], others, pads.pad_clearance_m)),
                    restaged=towards in restage,
                )
            )
    return out


def _same_layer(step: PartStep, steps: Sequence[PartStep]) -> list[tuple[str, Footprint]]:
    """The footprints of the other parts on ``step``'s layer."""
    return [
        (other.layout.part.name, other.layout.part.footprint)
        for other in steps
        if other.layout is not None
        and other.target.obj != step.target.obj
        and stacking.same_layer(other.target, step.target)
    ]


def warnings(plan: ArrangementPlan | None, limit: int = 6) -> list[str]:
    """The lines to print before a run: at most ``limit`` tight sides, then how many more."""
    if plan is None:
        return []
    sides = tight_sides(plan)
    lines = [side.text() for side in sides[:limit]]
    if len(sides) > limit:
        lines.append(f"and {len(sides) - limit} more side(s) where a neighbour leaves the pads no room")
    return lines
