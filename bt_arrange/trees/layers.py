"""The tree's share of arrangements in layers (issue 33): heights above the tower, standing, watching below.

``arrangement`` asks these when a plan has raised targets (``bt_arrange.stacking.layered``):

- ``stack_settings``: every move above the table rises over the finished tower (a held part's
  bottom ``approach_clearance_m`` minus its grasp height clear of the highest top face), since a
  joint-space carry from a pick beside the tower is free to pass over it at any height in between;
- ``check_correct_mode``: a plan in layers corrects each part before the next (``correct="each"``):
  placing a layer on parts not yet corrected would bury their errors;
- ``standing``: after the inspect after placing, ``CheckStanding`` confirms from depth that the part
  stands level on its support;
- ``regrasp_while_far``: a raised part placed ``REGRASP_OFFSET_MM`` or more off (or turned
  ``REGRASP_YAW_DEG`` or more) is picked up from its support and placed again before any push; a
  nearer one is pushed at its own height, gently (``Push(z_m=...)``, ``raised_push_limits``);
- ``watched_below``: after each placement, the parts below it that the camera still sees (no part
  above them yet, with ``OCCLUSION_MARGIN_M`` for the camera's slant) are looked at again and
  corrected when they moved, as neighbours are (``Recheck`` and a correction loop).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

import py_trees

from bt_arrange.behaviours import CheckStanding, GraspGuard, Pick, Place, keys
from bt_arrange.decorators import RepeatUntilWithin
from bt_arrange.errors import PlanError
from bt_arrange.footprints import overlap
from bt_arrange.geometry import PlanarPose
from bt_arrange.layout import Release
from bt_arrange.settings import ManipulationSettings
from bt_arrange.stacking import LEVEL_TOLERANCE_M, footprint_of, layered, top_m
from bt_arrange.trees.steps import inspect
from bt_arrange.trees.targets import Target

#: A lower part's top face counts as hidden when a part above comes within this (m) of its footprint:
#: the top camera looks down at a slant, so a part 5 cm higher and 10 cm off the optical axis hides
#: about 8 mm more of what lies beside it (70 cm camera: 50 mm x 100 / 600).
OCCLUSION_MARGIN_M = 0.01
#: A lower part counts as below a raised one when their footprints come within this (m): the layout's
#: neighbours (``bt_arrange.layout.neighbours_of``), so a tower's base and the parts around it, not a far one.
BELOW_WITHIN_M = 0.03
#: A raised part placed this far off or more (mm, by the camera) is picked up and placed again rather
#: than pushed: a push drags the support under it by friction for as long as it slides, and a part
#: pushed several millimetres across its support's edge has less of its margin left on the way.
#: A centred pick places within a millimetre (Table 1, row 1), so this is a placing gone wrong.
REGRASP_OFFSET_MM = 3.0
#: Or turned this far or more (deg): a square push turns a part back by a degree or two at a time.
REGRASP_YAW_DEG = 5.0
#: The most times a raised part is placed again before its correction is left to the pushes.
MAX_RAISED_REGRASPS = 2


def stack_settings(plan: Sequence[Target], settings: ManipulationSettings) -> ManipulationSettings:
    """The settings with ``approach_height_m`` over the plan's highest top face (unchanged on the table alone)."""
    if not layered(plan):
        return settings
    highest_m = max(top_m(t) for t in plan)
    approach_m = highest_m + settings.approach_clearance_m
    if approach_m <= settings.approach_height_m:
        return settings
    return dataclasses.replace(settings, approach_height_m=approach_m)


def check_correct_mode(plan: Sequence[Target], correct: str) -> None:
    """A plan in layers is corrected part by part: ``correct="after_all"`` is refused for it."""
    if correct == "after_all" and layered(plan):
        raised = next(t for t in plan if t.z_m > LEVEL_TOLERANCE_M)
        raise PlanError(
            f'correct = "after_all" places every part before correcting any, but target {raised.obj} stands on '
            'others: a plan in layers corrects each part before the next is put on it (correct = "each")',
            parts=(("target", raised.obj),),
        )


def same_layer(first: Target, second: Target) -> bool:
    """True when two targets stand at one height."""
    return abs(first.z_m - second.z_m) <= LEVEL_TOLERANCE_M


def standing(target: Target) -> list[py_trees.behaviour.Behaviour]:
    """``CheckStanding`` for a raised target, nothing for one on the table."""
    if target.z_m <= LEVEL_TOLERANCE_M:
        return []
    return [CheckStanding(f"{target.obj} stands on its support", target.obj, target.object_type, target.z_m)]


def hidden(lower: Target, placed: Sequence[Target], settings: ManipulationSettings) -> bool:
    """True when a part placed above ``lower`` comes within ``OCCLUSION_MARGIN_M`` of its footprint."""
    footprint = footprint_of(lower, settings)
    return any(
        other.z_m > lower.z_m + LEVEL_TOLERANCE_M
        and overlap(footprint, footprint_of(other, settings), OCCLUSION_MARGIN_M)
        for other in placed
    )


def watched_below(target: Target, placed: Sequence[Target], settings: ManipulationSettings) -> list[Target]:
    """The parts placed before ``target``, lower than it, that the camera still sees once it is down.

    Only for a raised target: placing one on the table is the planar layout's business (neighbours).
    """
    if target.z_m <= LEVEL_TOLERANCE_M:
        return []
    down = [*placed, target]
    near = footprint_of(target, settings)
    return [
        p
        for p in placed
        if p.z_m < target.z_m - LEVEL_TOLERANCE_M
        and overlap(near, footprint_of(p, settings), BELOW_WITHIN_M)
        and not hidden(p, down, settings)
    ]


def regrasp_while_far(
    target: Target, release: Release | None = None, kind_targets: Sequence[PlanarPose] = ()
) -> list[py_trees.behaviour.Behaviour]:
    """For a raised target: pick it up from its support and place it again while it lies far off (nothing else).

    ``release`` (a part among neighbours in its layer, ``plan_steps``): the pads pick it across the
    axis the layout gave its release, and release it so again; without it a pick off the support
    could bring a pad down into the 2 mm gap beside a neighbour (a pyramid's layer) and knock it off.
    ``kind_targets`` (identical parts): the inspection after placing it again tells it from its twins.

    After the inspect after placing (``/<obj>/offset_mm``, ``/<obj>/yaw_error_deg``)::

        RepeatUntilWithin "place <obj> again while 3 mm or 5 deg off"
        └── Sequence "pick <obj> off its support and place it again"
            ├── Pick "pick <obj> off its support"        at /<obj>/pose, z_m
            ├── GraspGuard ─ Place "place <obj> on its support again"
            ├── Inspect "inspect <obj> after placing it on its support again"
            └── CheckStanding

    A part nearer than that passes at once, in the same tick: nothing moves.
    """
    if target.z_m <= LEVEL_TOLERANCE_M:
        return []
    obj, kind, z_m = target.obj, target.object_type, target.z_m
    again = py_trees.composites.Sequence(
        name=f"pick {obj} off its support and place it again",
        memory=True,
        children=[
            Pick(f"pick {obj} off its support", obj, kind, grasp=release, z_m=z_m),
            GraspGuard(
                f"while holding {obj} over its support",
                Place(f"place {obj} on its support again", obj, kind, release=release, z_m=z_m),
            ),
            inspect(target, f"inspect {obj} after placing it on its support again", kind_targets=kind_targets),
            *standing(target),
        ],
    )
    return [
        RepeatUntilWithin(
            name=f"place {obj} again while {REGRASP_OFFSET_MM:g} mm or {REGRASP_YAW_DEG:g} deg off",
            child=again,
            offset_key=keys.key(obj, keys.OFFSET_MM),
            threshold_mm=REGRASP_OFFSET_MM,
            max_attempts=MAX_RAISED_REGRASPS,
            obj=obj,
            yaw_key=keys.key(obj, keys.YAW_ERROR_DEG),
            yaw_threshold_deg=REGRASP_YAW_DEG,
        )
    ]
