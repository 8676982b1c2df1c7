"""The tree's share of arrangements in layers: heights above the tower, standing, watching below.

``arrangement`` asks these when a plan has raised targets (``bt_arrange.plan.stacking.layered``):

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

from collections.abc import Sequence

import py_trees

from bt_arrange.behaviours import CheckStanding, GraspGuard, Pick, Place, keys
from bt_arrange.decorators import RepeatUntilWithin
from bt_arrange.geometry import PlanarPose
from bt_arrange.plan.layout import Release
from bt_arrange.plan.stacking import (
    LEVEL_TOLERANCE_M,
    check_correct_mode,
    same_layer,
    stack_settings,
    watched_below,
)
from bt_arrange.plan.targets import Target
from bt_arrange.trees.steps import inspect

#: A raised part placed this far off or more (mm, by the camera) is picked up and placed again rather
#: than pushed: a push drags the support under it by friction for as long as it slides, and a part
#: pushed several millimetres across its support's edge has less of its margin left on the way.
#: A centred pick places within a millimetre (Table 1, row 1), so this is a placing gone wrong.
REGRASP_OFFSET_MM = 3.0
#: Or turned this far or more (deg): a square push turns a part back by a degree or two at a time.
REGRASP_YAW_DEG = 5.0
#: The most times a raised part is placed again before its correction is left to the pushes.
MAX_RAISED_REGRASPS = 2


def standing(target: Target) -> list[py_trees.behaviour.Behaviour]:
    """``CheckStanding`` for a raised target, nothing for one on the table."""
    if target.z_m <= LEVEL_TOLERANCE_M:
        return []
    return [CheckStanding(f"{target.obj} stands on its support", target.obj, target.object_type, target.z_m)]


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


__all__ = [
    "check_correct_mode",
    "regrasp_while_far",
    "same_layer",
    "stack_settings",
    "standing",
    "watched_below",
]
